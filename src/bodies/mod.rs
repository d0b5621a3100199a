//! Rigid bodies: shapes and their signed distances, generated meshes, local level sets, the
//! body components and the contact kernel. Depends only on [`crate::base`].

mod body;
pub mod contact;
pub mod free_surface;
pub mod levelset;
pub mod meshgen;
pub mod shapes;
pub mod surface;

pub use body::*;
