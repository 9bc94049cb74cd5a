//! The stage "doors fuzz" (issue 27 item 8): the doors other than the scene loader fuzzed through
//! the `flinch` binary for a bounded time (host-harness/tests/fuzz_doors.rs: URDF, measured CSV,
//! merge-report mutations, command-line option values, file options pointed at special files; each
//! case under a 2 GiB address-space cap and a 20 s wall limit). `FLINCH_FUZZ_SECS` seconds (default
//! 60), as the loader fuzz. Owned by the io helper; registered with one line in main.rs.

use crate::host::run_ignored;
use crate::testpool::TestBinary;
use crate::Outcome;

/// The host tests' `fuzz_doors` binary, its ignored test ([`run_ignored`]: no second build).
pub fn doors_fuzz(bins: &[TestBinary]) -> Outcome {
    run_ignored(bins, "fuzz_doors", "the doors fuzz", "fuzz doors: ")
}
