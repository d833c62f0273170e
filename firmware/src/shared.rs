//! The state all tasks share: the protocol's [`Board`] core, the potentiometer sampler and the
//! status LED, behind one thread-mode mutex (every task runs in the one thread-mode executor,
//! so locking never masks an interrupt), plus the wake-up signals between tasks.
//!
//! Nothing here waits on a link: the board core queues frames in its own byte queue (a full
//! queue drops whole data frames and counts them in `Status`), and the transmit tasks are
//! only woken. Frames go out on the active link: the one that last delivered bytes (the serial
//! link until the host has spoken).

use core::cell::RefCell;
use core::sync::atomic::{AtomicU8, Ordering};

use embassy_sync::blocking_mutex::raw::ThreadModeRawMutex;
use embassy_sync::blocking_mutex::ThreadModeMutex;
use embassy_sync::signal::Signal;
use rig_protocol::device::{Action, Board};

use crate::board::StatusLed;
use crate::log::info;
use crate::pot::PotSampler;

/// The host links: the serial link (USART1 on the STM32, UART0 on the emulated board) and,
/// on the STM32, USB.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "stm32", derive(defmt::Format))]
pub enum LinkId {
    Serial = 0,
    #[cfg_attr(not(feature = "stm32"), allow(dead_code))]
    Usb = 1,
}

/// Board time: microseconds since boot (embassy-time's `Instant`, 1 MHz tick, widened to
/// `u64`: it does not wrap in the lifetime of the board).
pub fn now_us() -> u64 {
    embassy_time::Instant::now().as_micros()
}

/// Everything behind the mutex.
pub struct Shared {
    pub board: Board,
    pub pot: PotSampler,
    pub status_led: StatusLed,
}

static SHARED: ThreadModeMutex<RefCell<Option<Shared>>> = ThreadModeMutex::new(RefCell::new(None));
static TX_READY: [Signal<ThreadModeRawMutex, ()>; 2] = [Signal::new(), Signal::new()];
static SCHEDULE_CHANGED: Signal<ThreadModeRawMutex, ()> = Signal::new();
static ACTIVE_LINK: AtomicU8 = AtomicU8::new(LinkId::Serial as u8);

/// Installs the shared state (once, in `main`, before any task runs) and queues the `Hello`.
pub fn init(mut shared: Shared) {
    shared.board.boot(now_us());
    SHARED.lock(|cell| *cell.borrow_mut() = Some(shared));
    tx_ready();
}

/// Runs `f` on the shared state. Never call it from inside another `with`.
pub fn with<R>(f: impl FnOnce(&mut Shared) -> R) -> R {
    SHARED.lock(|cell| {
        let mut guard = cell.borrow_mut();
        match guard.as_mut() {
            Some(shared) => f(shared),
            None => panic!("shared::with before shared::init"),
        }
    })
}

/// Bytes from the host on `link`: makes `link` the active one, brings the potentiometer
/// samples up to date (so that a `Stop` ends the run with every sample taken before it), lets
/// the board core decode and answer, and applies the start/stop it asks for.
pub fn receive(link: LinkId, bytes: &[u8]) {
    ACTIVE_LINK.store(link as u8, Ordering::Relaxed);
    let action = with(|s| {
        let now = now_us();
        s.pot.drain(&mut s.board, now);
        let action = s.board.receive(now, bytes);
        match action {
            Action::None => {}
            Action::StartSampling(cfg) => {
                info!("start: {:?}", cfg);
                s.pot.start(cfg.pot_period_us);
                s.status_led.on();
            }
            Action::StopSampling => {
                info!("stop");
                s.pot.stop();
                s.status_led.off();
            }
        }
        action
    });
    if action != Action::None {
        SCHEDULE_CHANGED.signal(());
    }
    if action == Action::StopSampling {
        crate::stack::report();
    }
    tx_ready();
}

/// Wakes the transmit tasks: the board core may have queued frames.
pub fn tx_ready() {
    for signal in &TX_READY {
        signal.signal(());
    }
}

/// Moves queued bytes into `out` if `link` is the active link; returns how many.
pub fn pop_tx(link: LinkId, out: &mut [u8]) -> usize {
    if ACTIVE_LINK.load(Ordering::Relaxed) != link as u8 {
        return 0;
    }
    with(|s| s.board.tx_pop_into(out))
}

/// Waits until frames may be waiting for `link`.
pub async fn wait_tx(link: LinkId) {
    TX_READY[link as usize].wait().await;
}

/// Waits until a command started or stopped sampling.
pub async fn schedule_changed() {
    SCHEDULE_CHANGED.wait().await;
}
