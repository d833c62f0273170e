//! Every pin and peripheral the STM32 DAQ board uses, named by function.
//!
//! `hardware/PINMAP.md` lists the same names. The assignment is valid for the WeAct Black Pill
//! (STM32F411CEU6 / STM32F401CCU6, UFQFPN48) and for the 64-pin STM32F405RG / STM32F446RE, which
//! have the same pins and the same DMA request mapping (RM0383 / RM0090 / RM0390 "DMA2 request
//! mapping").
//!
//! | name          | pin / unit   | function                                              |
//! |---------------|--------------|-------------------------------------------------------|
//! | `pot_wiper`   | PA1, ADC1_IN1| potentiometer wiper (after the RC anti-alias filter) |
//! | `pot_adc`     | ADC1         | converts `pot_wiper` on each `pot_trigger` event      |
//! | `pot_dma`     | DMA2 stream 0| ADC1 -> RAM ring buffer (channel 0)                   |
//! | `pot_trigger` | TIM3 (TRGO)  | paces the ADC at the commanded pot rate               |
//! | `tilt_spi`    | SPI1         | the inclinometers' shared bus (mode 0, 2 MHz)         |
//! | `tilt_sck`    | PA5          | SPI1_SCK                                              |
//! | `tilt_miso`   | PA6          | SPI1_MISO                                             |
//! | `tilt_mosi`   | PA7          | SPI1_MOSI                                             |
//! | `tilt_cs0`    | PA4          | chip select of inclinometer 0 (active low)            |
//! | `tilt_cs1`    | PB0          | chip select of inclinometer 1 (active low)            |
//! | `tilt_cs2`    | PB1          | chip select of inclinometer 2 (active low)            |
//! | `link_uart`   | USART1       | host link, 921600 baud 8N1                            |
//! | `link_tx`     | PA9          | USART1_TX (board -> host)                             |
//! | `link_rx`     | PA10         | USART1_RX (host -> board)                             |
//! | `link_tx_dma` | DMA2 stream 7| USART1_TX (channel 4)                                 |
//! | `link_rx_dma` | DMA2 stream 2| USART1_RX (channel 4), circular                       |
//! | `usb_otg`     | USB_OTG_FS   | USB CDC-ACM host link                                 |
//! | `usb_dm`      | PA11         | USB D-                                                |
//! | `usb_dp`      | PA12         | USB D+                                                |
//! | `status_led`  | PC13         | on-board blue LED, active low                         |
//!
//! Timers: TIM9 is embassy-time's driver (feature `time-driver-tim9`); TIM3 is `pot_trigger`.

use embassy_stm32::peripherals::{
    ADC1, DMA2_CH0, DMA2_CH2, DMA2_CH7, PA1, PA10, PA11, PA12, PA4, PA5, PA6, PA7, PA9, PB0, PB1,
    PC13, SPI1, TIM3, USART1, USB_OTG_FS,
};
use embassy_stm32::{Peri, Peripherals};

/// Number of inclinometer chip selects on the board.
pub const TILT_SENSORS_MAX: usize = 3;

/// The potentiometer channel: ADC, pin, DMA stream and trigger timer.
pub struct PotPins {
    pub pot_adc: Peri<'static, ADC1>,
    pub pot_wiper: Peri<'static, PA1>,
    pub pot_dma: Peri<'static, DMA2_CH0>,
    pub pot_trigger: Peri<'static, TIM3>,
}

/// The inclinometers' SPI bus and chip selects.
pub struct TiltPins {
    pub tilt_spi: Peri<'static, SPI1>,
    pub tilt_sck: Peri<'static, PA5>,
    pub tilt_miso: Peri<'static, PA6>,
    pub tilt_mosi: Peri<'static, PA7>,
    pub tilt_cs0: Peri<'static, PA4>,
    pub tilt_cs1: Peri<'static, PB0>,
    pub tilt_cs2: Peri<'static, PB1>,
}

/// The USART host link.
pub struct LinkPins {
    pub link_uart: Peri<'static, USART1>,
    pub link_tx: Peri<'static, PA9>,
    pub link_rx: Peri<'static, PA10>,
    pub link_tx_dma: Peri<'static, DMA2_CH7>,
    pub link_rx_dma: Peri<'static, DMA2_CH2>,
}

/// The USB full-speed host link.
pub struct UsbPins {
    pub usb_otg: Peri<'static, USB_OTG_FS>,
    pub usb_dm: Peri<'static, PA11>,
    pub usb_dp: Peri<'static, PA12>,
}

/// The whole board, split by function.
pub struct Board {
    pub pot: PotPins,
    pub tilt: TiltPins,
    pub link: LinkPins,
    pub usb: UsbPins,
    pub status_led: Peri<'static, PC13>,
}

impl Board {
    /// Takes the pins and units this firmware uses out of the HAL's peripherals.
    pub fn new(p: Peripherals) -> Self {
        Self {
            pot: PotPins {
                pot_adc: p.ADC1,
                pot_wiper: p.PA1,
                pot_dma: p.DMA2_CH0,
                pot_trigger: p.TIM3,
            },
            tilt: TiltPins {
                tilt_spi: p.SPI1,
                tilt_sck: p.PA5,
                tilt_miso: p.PA6,
                tilt_mosi: p.PA7,
                tilt_cs0: p.PA4,
                tilt_cs1: p.PB0,
                tilt_cs2: p.PB1,
            },
            link: LinkPins {
                link_uart: p.USART1,
                link_tx: p.PA9,
                link_rx: p.PA10,
                link_tx_dma: p.DMA2_CH7,
                link_rx_dma: p.DMA2_CH2,
            },
            usb: UsbPins {
                usb_otg: p.USB_OTG_FS,
                usb_dm: p.PA11,
                usb_dp: p.PA12,
            },
            status_led: p.PC13,
        }
    }
}
