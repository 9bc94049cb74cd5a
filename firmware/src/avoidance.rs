//! On-board collision-avoidance step (Ch. 5 of the thesis). Filled by the avoidance issue.
