//! The inclinometers on the STM32: up to three Murata SCL3300 on SPI1, one chip select each.
//!
//! At boot every chip select is probed: a sensor that starts up in mode 1 (1.2 g full scale,
//! 6000 counts/g, 40 Hz low-pass) and answers its WHOAMI counts as present; the count goes into
//! `Hello.tilt_sensors`. The `scl3300` driver checks each SPI frame's CRC-8 and return-status
//! bits.
//!
//! SPI is blocking: one sensor read is 5 frames of 32 bits at 1.5 MHz with the 10 us gaps the
//! sensor needs, about 0.2 ms, short enough not to disturb the links (the ADC runs by DMA).

use core::cell::RefCell;

use defmt::{info, warn};
use embassy_stm32::gpio::{Level, Output, Speed};
use embassy_stm32::mode::Blocking;
use embassy_stm32::spi::mode::Master;
use embassy_stm32::spi::{self, Spi};
use embassy_stm32::time::Hertz;
use embassy_time::Delay;
use embedded_hal_bus::spi::RefCellDevice;
use heapless::Vec;
use rig_protocol::TiltReading;
use scl3300::{Acceleration, ComponentId, MeasurementMode, Normal, Scl3300, Temperature};
use static_cell::StaticCell;

use super::pins::{TiltPins, TILT_SENSORS_MAX};

type TiltBus = Spi<'static, Blocking, Master>;
type TiltDevice = RefCellDevice<'static, TiltBus, Output<'static>, Delay>;
type Sensor = Scl3300<TiltDevice, Normal>;

/// SCL3300 SPI clock, well inside the sensor's range; the HAL rounds the divider down (1.5 MHz
/// from the 96 MHz APB2 clock).
const TILT_SPI_HZ: u32 = 2_000_000;

static BUS: StaticCell<RefCell<TiltBus>> = StaticCell::new();

/// A failed inclinometer read (already logged).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TiltReadError;

/// The sensors that answered at boot, with their chip-select index.
pub struct TiltSensors {
    sensors: Vec<(u8, Sensor), TILT_SENSORS_MAX>,
}

impl TiltSensors {
    /// Number of sensors found.
    pub fn count(&self) -> u8 {
        self.sensors.len() as u8
    }

    /// Reads the `slot`-th sensor found at boot (the scheduler counts only those).
    pub fn read(&mut self, slot: u8, t_us: u64) -> Result<TiltReading, TiltReadError> {
        let (index, sensor) = self
            .sensors
            .get_mut(usize::from(slot))
            .ok_or(TiltReadError)?;
        match sensor.read::<(Acceleration, Temperature)>() {
            Ok((acc, temp)) => Ok(TiltReading {
                sensor: *index,
                t_us,
                // Two's complement on the wire; the driver hands out the raw u16.
                x: acc.x_raw() as i16,
                y: acc.y_raw() as i16,
                z: acc.z_raw() as i16,
                temp: temp.raw() as i16,
                status: 0, // the driver rejects any frame whose return status is not normal
            }),
            Err(e) => {
                warn!("tilt {}: read failed ({})", index, error_name(&e));
                Err(TiltReadError)
            }
        }
    }
}

/// Opens SPI1 and starts every sensor that answers.
pub fn probe(pins: TiltPins) -> TiltSensors {
    let mut config = spi::Config::default();
    config.mode = spi::MODE_0;
    config.frequency = Hertz(TILT_SPI_HZ);
    // A missing sensor then reads as all ones, which fails the CRC.
    config.miso_pull = embassy_stm32::gpio::Pull::Up;
    let bus = Spi::new_blocking(
        pins.tilt_spi,
        pins.tilt_sck,
        pins.tilt_mosi,
        pins.tilt_miso,
        config,
    );
    let bus: &'static RefCell<TiltBus> = BUS.init(RefCell::new(bus));

    let chip_selects = [
        Output::new(pins.tilt_cs0, Level::High, Speed::VeryHigh),
        Output::new(pins.tilt_cs1, Level::High, Speed::VeryHigh),
        Output::new(pins.tilt_cs2, Level::High, Speed::VeryHigh),
    ];
    let mut sensors = Vec::new();
    for (index, cs) in (0u8..).zip(chip_selects) {
        let Ok(device) = RefCellDevice::new(bus, cs, Delay);
        match start_sensor(device) {
            Ok(sensor) => {
                info!("tilt {}: SCL3300 ready", index);
                // Capacity equals the number of chip selects: this push cannot fail.
                let _ = sensors.push((index, sensor));
            }
            Err(reason) => info!("tilt {}: no sensor ({})", index, reason),
        }
    }
    TiltSensors { sensors }
}

fn start_sensor(device: TiltDevice) -> Result<Sensor, &'static str> {
    let mut sensor = Scl3300::new(device)
        .start_up(MeasurementMode::FullScale12)
        .map_err(|_| "start-up failed")?;
    match sensor.read::<ComponentId>() {
        Ok(id) if id == ComponentId::WHOAMI => Ok(sensor),
        Ok(_) => Err("wrong WHOAMI"),
        Err(_) => Err("WHOAMI read failed"),
    }
}

fn error_name<E>(error: &scl3300::Error<E>) -> &'static str {
    match error {
        scl3300::Error::Startup => "start-up in progress",
        scl3300::Error::ReturnStatus => "return status: error",
        scl3300::Error::Crc => "CRC mismatch",
        scl3300::Error::Spi(_) => "SPI",
    }
}
