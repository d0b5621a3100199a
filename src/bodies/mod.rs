//! Rigid bodies: shapes and their signed distances, generated meshes, local level sets, the
//! body components, the integrals over a body's patch ([`integrals`]), the state the pressure
//! coupling carries between steps ([`coupling`]) and the contact kernel. Depends only on
//! [`crate::base`].

mod body;
pub mod contact;
pub mod coupling;
pub mod free_surface;
pub mod integrals;
pub mod levelset;
pub mod markers;
pub mod meshgen;
pub mod shapes;
pub mod surface;

pub use body::*;
