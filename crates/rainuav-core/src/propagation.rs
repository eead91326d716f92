//! Propagation, one layer: the split-step parabolic equation ([`pwe`]) and the ray engine over
//! ground, terrain and buildings: the rays of every cell and pixel ([`rays`], in time
//! [`raytime`]), the profile of a path and its diffraction ([`path`], [`diffraction`],
//! [`obstacles`]), the corners' and roof edges' rays ([`corners`]), the walls' reflections once
//! ([`walls`]) and twice ([`walls2`]) and the lines of sight ([`sight`]).

pub mod corners;
pub mod diffraction;
pub(crate) mod grid;
pub mod obstacles;
pub mod path;
pub mod pwe;
pub mod rays;
pub mod raytime;
pub mod sight;
pub(crate) mod tiers;
pub mod walls;
pub mod walls2;
