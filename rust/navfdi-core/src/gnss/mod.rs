//! GNSS: geometry, constellations, pseudorange models and snapshot fault detection and
//! exclusion (METHODS §10).
//!
//! * [`geodesy`]: WGS-84 geodetic ⇄ ECEF, local ENU frame, elevation and azimuth.
//! * [`clock`]: the receiver clock model (bias and drift) of the tight filters.
//! * [`ranges`]: the measurement stream of a `gnss_ranges` sensor (satellites in view per
//!   epoch, their tight-coupling rows); [`innovation`], [`pv_filter`]: innovation FDE and the
//!   GNSS-only filter of the tight architecture.
//! * [`constellation`]: nominal circular-orbit constellations (GPS and Galileo as Walker
//!   patterns), satellite positions and velocities in ECEF.
//! * [`rinex_text`]: reading a RINEX file's text and checking its structure line by line.
//! * [`rinex`]: RINEX 3 observation and navigation files (read with the `rinex` crate).
//! * [`broadcast`]: GPS time, broadcast-ephemeris satellite positions and clocks, selection.
//! * [`atmosphere`]: Klobuchar ionosphere and Saastamoinen troposphere.
//! * [`prefilter`]: channel prefilters of an ultra-tight receiver and discriminator noise.
//! * [`sequential`]: SPRT and rate CUSUM on each satellite's residual stream.
//! * [`spp`]: single-point positioning with satellite FDE on real pseudoranges.
//! * [`lsq`]: weighted least squares, the global test and w-test, Gauss-Newton.
//! * [`snapshot`]: iterative weighted least squares for position and clock from
//!   pseudoranges, and the global test + Baarda w-test exclusion loop (also used on
//!   pseudorange rates for velocity and clock drift).

pub mod atmosphere;
pub mod broadcast;
pub mod clock;
pub mod constellation;
pub mod doppler;
pub mod geodesy;
pub mod innovation;
pub mod lsq;
pub mod prefilter;
pub mod pv_filter;
pub mod ranges;
pub mod rinex;
pub mod rinex2;
pub mod rinex_text;
pub mod sequential;
pub mod signals;
pub mod snapshot;
pub mod spp;

/// Speed of light in vacuum (m/s).
pub const C: f64 = 299_792_458.0;
