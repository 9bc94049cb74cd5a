//! The board's firmware instance: the concrete `Firmware` type over this board's pins and clock,
//! its one static (`FW`, shared by the edge, tick and bookkeeping handlers, the diagnostics and the
//! log drain through `IsrCell`), and the NVIC priorities those handlers run at. Kept out of
//! `board.rs` so that the diagnostics and the log drain use it without importing the binary's root.

use crate::hw::{In, Out, Tim2, ESC_PIN, ESC_PORT, K1_PIN, K1_PORT, K2_PIN, K2_PORT, PA, SUPPLY_PIN, SUPPLY_PORT};
use crate::isr_cell::IsrCell;
use flinch_firmware::{DualSwitch, Edm, Firmware};

/// NVIC priorities (upper 4 bits on the F407; lower number = more urgent).
/// The edge at 0x10, not 0: the configurable faults (MemManage, BusFault, UsageFault) are at 0,
/// above every interrupt, so a stack overflow in any handler is taken, not escalated
/// (`support/board_faults.rs`).
pub(crate) const PRIO_EDGE: u8 = 0x10;
pub(crate) const PRIO_TICK: u8 = 0x80;

pub(crate) type Switch = DualSwitch<In<PA, 0>, In<PA, 4>, Out<SUPPLY_PORT, SUPPLY_PIN>>;
pub(crate) type K1 = Out<K1_PORT, K1_PIN>;
pub(crate) type K2 = Out<K2_PORT, K2_PIN>;
pub(crate) type Esc = Out<ESC_PORT, ESC_PIN>;
pub(crate) type Fw = Firmware<Tim2, Switch, K1, K2, Esc, In<PA, 1>, 16, Edm<In<PA, 2>, In<PA, 3>>>;
pub(crate) static FW: IsrCell<Fw> = IsrCell::new();

