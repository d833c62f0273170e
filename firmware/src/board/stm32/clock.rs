//! The STM32's clock tree.
//!
//! Every chip runs from its crystal (HSE) through the main PLL, with PLL_Q at exactly 48 MHz for
//! USB FS. The crystal and the dividers depend on the chip feature:
//!
//! | feature     | HSE    | SYSCLK  | APB1 / APB2  | PLL: M, N, P, Q  |
//! |-------------|--------|---------|--------------|------------------|
//! | `stm32f411` | 25 MHz | 96 MHz  | 48 / 96 MHz  | 25, 192, 2, 4    |
//! | `stm32f401` | 25 MHz | 84 MHz  | 42 / 84 MHz  | 25, 336, 4, 7    |
//! | `stm32f446` | 8 MHz  | 168 MHz | 42 / 84 MHz  | 8, 336, 2, 7     |
//! | `stm32f405` | 8 MHz  | 168 MHz | 42 / 84 MHz  | 8, 336, 2, 7     |
//!
//! Board time (`crate::shared::now_us`) is embassy-time's `Instant`, 1 MHz tick, driven by TIM9.

use embassy_stm32::rcc::{
    AHBPrescaler, APBPrescaler, Hse, HseMode, Pll, PllMul, PllPDiv, PllPreDiv, PllQDiv, PllSource,
    Sysclk,
};
use embassy_stm32::time::Hertz;
use embassy_stm32::Config;

#[cfg(any(feature = "stm32f411", feature = "stm32f401"))]
const HSE_HZ: u32 = 25_000_000;
#[cfg(any(feature = "stm32f446", feature = "stm32f405"))]
const HSE_HZ: u32 = 8_000_000;

/// The HAL configuration: clocks from the crystal, 48 MHz for USB.
pub fn config() -> Config {
    let mut config = Config::default();
    let rcc = &mut config.rcc;
    rcc.hse = Some(Hse {
        freq: Hertz(HSE_HZ),
        mode: HseMode::Oscillator,
    });
    rcc.pll_src = PllSource::HSE;
    rcc.sys = Sysclk::PLL1_P;
    rcc.ahb_pre = AHBPrescaler::DIV1;

    #[cfg(feature = "stm32f411")]
    {
        rcc.pll = Some(Pll {
            prediv: PllPreDiv::DIV25,
            mul: PllMul::MUL192,
            divp: Some(PllPDiv::DIV2),
            divq: Some(PllQDiv::DIV4),
            divr: None,
        });
        rcc.apb1_pre = APBPrescaler::DIV2;
        rcc.apb2_pre = APBPrescaler::DIV1;
    }
    #[cfg(feature = "stm32f401")]
    {
        rcc.pll = Some(Pll {
            prediv: PllPreDiv::DIV25,
            mul: PllMul::MUL336,
            divp: Some(PllPDiv::DIV4),
            divq: Some(PllQDiv::DIV7),
            divr: None,
        });
        rcc.apb1_pre = APBPrescaler::DIV2;
        rcc.apb2_pre = APBPrescaler::DIV1;
    }
    #[cfg(any(feature = "stm32f446", feature = "stm32f405"))]
    {
        rcc.pll = Some(Pll {
            prediv: PllPreDiv::DIV8,
            mul: PllMul::MUL336,
            divp: Some(PllPDiv::DIV2),
            divq: Some(PllQDiv::DIV7),
            divr: None,
        });
        rcc.apb1_pre = APBPrescaler::DIV4;
        rcc.apb2_pre = APBPrescaler::DIV2;
    }
    #[cfg(feature = "stm32f446")]
    {
        rcc.mux.clk48sel = embassy_stm32::rcc::mux::Clk48sel::PLL1_Q;
    }
    config
}
