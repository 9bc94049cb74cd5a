//! [`KinError`]: a URDF, chain or configuration that cannot be used, with where and what.

use std::fmt;

/// A URDF, chain or configuration that cannot be used, with where and what.
#[derive(Debug, Clone, PartialEq)]
pub struct KinError {
    /// The URDF file (or the label given for a string).
    pub file: String,
    /// The element at fault: `link "x"`, `joint "y"`, `joints`, `direction`, ...
    pub element: String,
    /// What is wrong and what is allowed.
    pub what: String,
}

impl KinError {
    pub(crate) fn new(file: &str, element: impl Into<String>, what: impl Into<String>) -> Self {
        KinError { file: file.to_string(), element: element.into(), what: what.into() }
    }
}

impl fmt::Display for KinError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}: {}", self.file, self.element, self.what)
    }
}

impl std::error::Error for KinError {}
