//! The time history as CSV: one row per recorded sample, SI units in the header.

use crate::sim::Sample;
use std::io::{self, Write};

/// Column headers, with units.
pub const HEADER: &str = "t_s,v_c_m_s,v_r_m_s,v_t_m_s,v_p_m_s,s_m,f_contact_n,f_robot_n,f_spring_n,f_stops_n,f_friction_n";

/// Writes the history.
pub fn write(out: &mut dyn Write, history: &[Sample]) -> io::Result<()> {
    writeln!(out, "{HEADER}")?;
    for s in history {
        writeln!(out, "{:.9},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e}",
            s.t, s.v_c, s.v_r, s.v_t, s.v_p, s.s, s.f_contact, s.f_robot, s.f_spring, s.f_stops, s.f_friction)?;
    }
    Ok(())
}
