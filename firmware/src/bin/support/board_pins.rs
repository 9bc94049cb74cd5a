//! The board's pin map (firmware/README.md "Output architecture"): the GPIO ports by number and the
//! pins of the stop channels, the category-0 escalation and the sensor supply. Constants only, no
//! imports: `board_hw.rs` (the registers and pin types) and the QEMU bench's pin image
//! (`board_pin_image.rs`) both read it, neither imports the other.

/// The GPIO ports by letter (A = 0 .. I = 8), the pins' const-generic port; `gpio` gives the PAC's
/// register block of each.
pub(crate) const PA: u8 = 0;
pub(crate) const PB: u8 = 1;
pub(crate) const PD: u8 = 3;
pub(crate) const PE: u8 = 4;
/// GPIOI: unused on the board; the `qemu-io` bench writes its markers to its BSRR.
pub(crate) const PI: u8 = 8;

// ---- Inputs on GPIOA; the two stop
// channels and the category-0 escalation on three other ports, one each, each with its own RCC
// AHB1ENR clock-enable bit, so a frozen port (clock gated) or a dead port takes one output only ----
/// Stop channel K1: PD12 (GPIOD, AHB1ENR.GPIODEN; the Discovery's green LED shows it).
pub(crate) const K1_PORT: u8 = PD;
pub(crate) const K1_PIN: u32 = 12;
/// Stop channel K2: PE12 (GPIOE, AHB1ENR.GPIOEEN).
pub(crate) const K2_PORT: u8 = PE;
pub(crate) const K2_PIN: u32 = 12;
/// The category-0 escalation: PB12 (GPIOB, AHB1ENR.GPIOBEN).
pub(crate) const ESC_PORT: u8 = PB;
pub(crate) const ESC_PIN: u32 = 12;
/// The sensor supply: PD14 (with K1 on GPIOD).
pub(crate) const SUPPLY_PORT: u8 = PD;
pub(crate) const SUPPLY_PIN: u32 = 14;

