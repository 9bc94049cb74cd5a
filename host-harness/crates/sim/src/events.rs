//! The event functions' indices: 0 tool-target contact onset/separation, 1 front end-stop
//! entry/exit, 2 back end-stop entry/exit, 3 the sensor's threshold, 4-6 the instants where the
//! contact, the front stop or the back stop stops pushing while still penetrated, 7 a Coulomb
//! slide's stick/slip switch (the crate's first comment says why each is located).

/// Number of event functions.
pub const E: usize = 8;
pub(crate) const EV_CONTACT: usize = 0;
pub(crate) const EV_FRONT: usize = 1;
pub(crate) const EV_BACK: usize = 2;
pub(crate) const EV_SWITCH: usize = 3;
pub(crate) const EV_CONTACT_PUSH: usize = 4;
pub(crate) const EV_FRONT_PUSH: usize = 5;
pub(crate) const EV_BACK_PUSH: usize = 6;
pub(crate) const EV_SLIDE: usize = 7;
