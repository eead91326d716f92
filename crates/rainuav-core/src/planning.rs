//! Planning, one layer: the exact planners, in the plane and in space and time ([`planner`]), and
//! among flight levels ([`planlevels`]), and the signal a UAV reads along its flight
//! ([`sampling`]).

pub mod planlevels;
pub mod planner;
pub mod sampling;
