//! The unit of an output field from its name (docs/conventions.md): the convention's suffixes
//! (`_s`, `_m`, `_mps`, `_n`, ...) and, for the scene contract's older names, a table.

/// Units by suffix (docs/conventions.md).
pub const SUFFIXES: &[(&str, &str)] = &[
    ("_n_per_m", "N/m"), ("_ns_per_m", "N s/m"), ("_mps2", "m/s^2"), ("_mps", "m/s"), ("_pa", "Pa"), ("_kg", "kg"), ("_hz", "Hz"), ("_bps", "bit/s"),
    ("_m2", "m^2"), ("_px", "px"), ("_rad", "rad"), ("_deg", "deg"), ("_j", "J"), ("_n_s", "N s"), ("_s", "s"), ("_m", "m"), ("_n", "N"),
];

/// Units of the scene contract's summary names and of the dimensionless fields ("1").
pub const NAMED: &[(&str, &str)] = &[
    ("t_contact", "s"), ("t_detect", "s"), ("t_brake", "s"), ("t_stop", "s"), ("detection_delay", "s"), ("reaction_time", "s"),
    ("peak_contact_force", "N"), ("peak_robot_force", "N"), ("object_final_velocity", "m/s"), ("object_peak_velocity", "m/s"),
    ("approach_speed_mps", "m/s"), ("max_travel", "m"), ("decoupler_impulse", "N s"), ("peak_gas_pressure", "Pa"),
    ("mode", "1"), ("achieved_restitution", "1"), ("steps", "1"), ("rhs_evals", "1"), ("contacts", "1"), ("rejected_steps", "1"),
    ("events", "1"), ("schema_version", "1"), ("points", "1"), ("seq", "1"), ("flags", "1"),
    // avoid: counts.
    ("heading_reversals", "1"), ("stalls", "1"), ("frames", "1"), ("good", "1"), ("bad_crc", "1"), ("bad_header", "1"), ("short", "1"), ("stale", "1"),
    ("skipped_bytes", "1"), ("overrun_bytes", "1"), ("new_sessions", "1"), ("old_session", "1"), ("backlog", "1"),
    ("ssm_violations", "1"), ("steps_in_pfl", "1"), ("contacts_within_pfl", "1"),
    // hil: the phase is a fraction of the scan cycle.
    ("phase", "1"),
    // --measured: each comparison states its unit in its own `unit` field.
    ("rms_error", "given by the comparison's `unit`"), ("rms_error_shifted", "given by the comparison's `unit`"), ("peak_measured", "given by the comparison's `unit`"),
    ("peak_simulated", "given by the comparison's `unit`"), ("peak_error", "given by the comparison's `unit`"),
];

/// The unit of a field name, if the convention or the table gives one.
pub fn unit_of(name: &str) -> Option<&'static str> {
    NAMED.iter().find(|(n, _)| *n == name).map(|(_, u)| *u).or_else(|| SUFFIXES.iter().find(|(s, _)| name.ends_with(s)).map(|(_, u)| *u))
}
