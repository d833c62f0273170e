//! Log macros shared by both boards: `info!` and `warning!` go to defmt (RTT) on the STM32 and to
//! semihosting text on the emulated board. Format strings must suit both: `{}` for integers
//! and strings, `{:?}` for the protocol's types (they implement `Debug` and `defmt::Format`).

#[cfg(feature = "stm32")]
macro_rules! info {
    ($($arg:tt)*) => { defmt::info!($($arg)*) };
}
#[cfg(feature = "stm32")]
macro_rules! warning {
    ($($arg:tt)*) => { defmt::warn!($($arg)*) };
}

#[cfg(feature = "mps2-an386")]
macro_rules! info {
    ($($arg:tt)*) => { $crate::board::log_line("INFO", format_args!($($arg)*)) };
}
#[cfg(feature = "mps2-an386")]
macro_rules! warning {
    ($($arg:tt)*) => { $crate::board::log_line("WARN", format_args!($($arg)*)) };
}

pub(crate) use {info, warning};
