//! GNSS: geometry, constellations, pseudorange models and snapshot fault detection and
//! exclusion (METHODS §10).
//!
//! * [`geodesy`]: WGS-84 geodetic ⇄ ECEF, local ENU frame, elevation and azimuth.
//! * [`constellation`]: nominal circular-orbit constellations (GPS and Galileo as Walker
//!   patterns), satellite positions and velocities in ECEF.
//! * [`snapshot`]: iterative weighted least squares for position and clock from
//!   pseudoranges, and the global test + Baarda w-test exclusion loop (also used on
//!   pseudorange rates for velocity and clock drift).

pub mod constellation;
pub mod geodesy;
pub mod innovation;
pub mod pv_filter;
pub mod ranges;
pub mod snapshot;

/// Speed of light in vacuum (m/s).
pub const C: f64 = 299_792_458.0;
