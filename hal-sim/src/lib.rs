//! Stateful `embedded-hal` fakes driven by the plant simulation.
