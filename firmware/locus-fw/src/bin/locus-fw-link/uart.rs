//! A polling driver for the ARM CMSDK APB UART (Cortex-M System Design Kit
//! TRM, ARM DDI0479C), UART0 of QEMU's `mps2-an386` at `0x4000_4000`
//! (QEMU `hw/arm/mps2.c`; its model is `hw/char/cmsdk-apb-uart.c`).
//!
//! The UART has a one-byte buffer each way and no FIFO: [`Uart::write`]
//! waits while the transmit buffer is full, [`Uart::read`] takes the
//! received byte if there is one. A byte that arrives while the receive
//! buffer is still full overwrites it and sets the overrun flag, which
//! [`Uart::take_rx_overrun`] reads and clears: the firmware counts it (QEMU
//! never overruns: it hands the UART a byte only when the buffer is
//! empty, and the pseudo-terminal holds the rest).

use core::sync::atomic::{AtomicBool, Ordering};

/// UART0's registers on `mps2-an386`.
const UART0: usize = 0x4000_4000;
/// Data: write to send a byte, read to take the received one.
const DATA: usize = 0x000;
/// State: bit 0 TX buffer full, bit 1 RX buffer full, bit 2 TX overrun,
/// bit 3 RX overrun (overrun bits are write-one-to-clear).
const STATE: usize = 0x004;
/// Control: bit 0 TX enable, bit 1 RX enable (interrupts stay disabled).
const CTRL: usize = 0x008;
/// Baud rate divider: `PCLK / baud`, at least 16.
const BAUDDIV: usize = 0x010;

const STATE_TX_FULL: u32 = 1 << 0;
const STATE_RX_FULL: u32 = 1 << 1;
const STATE_RX_OVERRUN: u32 = 1 << 3;
const CTRL_TX_EN: u32 = 1 << 0;
const CTRL_RX_EN: u32 = 1 << 1;

/// Whether UART0 has been handed out.
static TAKEN: AtomicBool = AtomicBool::new(false);

/// UART0, owned: at most one value exists ([`Uart::take`]).
pub struct Uart {
    base: usize,
}

impl Uart {
    /// UART0 set to `PCLK / bauddiv` baud (QEMU's UARTs run from the
    /// 25 MHz board clock; the divider must be at least 16, QEMU ignores
    /// the rate itself), transmitter and receiver enabled, no interrupts.
    /// `None` if it was taken already.
    pub fn take(bauddiv: u32) -> Option<Self> {
        if TAKEN.swap(true, Ordering::AcqRel) {
            return None;
        }
        let mut uart = Self { base: UART0 };
        uart.set(BAUDDIV, bauddiv.max(16));
        uart.set(CTRL, CTRL_TX_EN | CTRL_RX_EN);
        Some(uart)
    }

    #[allow(unsafe_code)]
    fn get(&self, offset: usize) -> u32 {
        // SAFETY: an aligned word register of UART0's 4 KiB block, which
        // this value owns; reads have no side effect but on DATA (taking
        // the received byte), which only `read` reads.
        unsafe { core::ptr::read_volatile((self.base + offset) as *const u32) }
    }

    #[allow(unsafe_code)]
    fn set(&mut self, offset: usize, value: u32) {
        // SAFETY: as in `get`; writes to UART0's registers, owned here.
        unsafe { core::ptr::write_volatile((self.base + offset) as *mut u32, value) }
    }

    /// Sends `bytes`, waiting for the transmit buffer before each.
    pub fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            while self.get(STATE) & STATE_TX_FULL != 0 {}
            self.set(DATA, u32::from(b));
        }
    }

    /// The received byte, if one is waiting.
    pub fn read(&mut self) -> Option<u8> {
        if self.get(STATE) & STATE_RX_FULL == 0 {
            return None;
        }
        #[allow(clippy::cast_possible_truncation)] // DATA holds one byte
        Some(self.get(DATA) as u8)
    }

    /// Whether a received byte was overwritten since the last call
    /// (clears the flag).
    pub fn take_rx_overrun(&mut self) -> bool {
        let overrun = self.get(STATE) & STATE_RX_OVERRUN != 0;
        if overrun {
            self.set(STATE, STATE_RX_OVERRUN);
        }
        overrun
    }
}
