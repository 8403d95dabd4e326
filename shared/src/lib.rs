//! Shared core of triquint: everything the host planner, the drive firmware
//! and the virtual hardware must agree on, bit for bit.
//!
//! One concept per module:
//! - [`machine`]: the machine file's machine: robot, homing, axes, ceilings.
//! - [`params`]: machine parameters (paper Table 1) and motion limits (Table 3).
//! - [`kinematics`]: inverse/forward kinematics and Jacobians of the 3-PUU.
//! - [`dynamics`]: inverse dynamics by virtual work (the feedforward the drives run).
//! - [`lagrangian`]: an independent Lagrangian formulation (checks and plant model).
//! - [`quintic`]: quintic segment evaluation by Horner's rule.
//! - [`plan`]: the plan file that the planner writes (needs `alloc`).
//! - [`readable`]: numbers for one-line messages (needs `alloc`).
#![no_std]
#![forbid(unsafe_code)]

#[cfg(feature = "alloc")]
extern crate alloc;
#[cfg(any(feature = "std", test))]
extern crate std;

#[cfg(feature = "std")]
pub mod bounded_read;
pub mod dynamics;
pub mod kinematics;
pub mod lagrangian;
pub mod machine;
pub mod params;
#[cfg(feature = "alloc")]
pub mod plan;
pub mod protocol;
pub mod quintic;
#[cfg(feature = "alloc")]
pub mod readable;

pub use kinematics::KinematicsError;
pub use params::{Limits, Model, Robot, Travel};

/// The scalar type the generic math runs on: `f64` on the host, `f32` on the drives.
pub trait Real: nalgebra::RealField + Copy {}
impl<T: nalgebra::RealField + Copy> Real for T {}

/// Converts an `f64` constant into the working precision.
#[inline(always)]
pub(crate) fn c<T: Real>(x: f64) -> T {
    nalgebra::convert(x)
}
