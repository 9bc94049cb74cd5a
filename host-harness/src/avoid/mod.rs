//! Collision avoidance (Ch. 5): RBF interpolation of depth images and the potential field.
