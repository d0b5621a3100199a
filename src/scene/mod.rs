//! Scenes: what to simulate, read from RON files.
//!
//! Every struct rejects unknown fields, every field has a documented unit and default, and
//! every problem found while loading is a [`SceneError`] that names the file, the line and the
//! field, so a user can fix the scene without reading code.
//!
//! ```ron
//! Scene(
//!     name: "lamb-oseen",
//!     domain: (extent: [2.0, 2.0], origin: [-1.0, -1.0], cells: [128, 128]),
//!     fluid: (viscosity: 1e-3),
//!     numerics: (end_time: 2.5, dt: Adaptive(c: 0.5, dt_max: 0.05)),
//!     initial: [LambOseen(center: [0.0, 0.0], circulation: 1.0, core_radius: 0.1)],
//!     output: (every: 0.5),
//! )
//! ```
//!
//! The files: [`format`] (the serde structs, every field documented), [`check`] (one check per
//! type), [`error`] (errors and their locations), [`kappa`] (the default contact strength from
//! the scene's scales), [`generate`] (body generators, expanded into bodies), [`overlap`] (bodies overlapping at the start), [`resolved`] (the
//! defaults worked out from other settings, once), [`steps`] (the largest step a scene allows
//! and the fewest steps to its end) and [`valid`] (the [`ValidScene`] that only
//! those checks make, the only scene the engine takes).

pub mod check;
pub mod error;
pub mod format;
pub mod generate;
pub mod kappa;
mod liquid;
pub mod overlap;
pub mod resolved;
pub mod steps;
pub mod valid;

pub use crate::base::params::{BodyCoupling, InterfaceAcceleration, RemeshKernel, TimeStep};
pub use crate::bodies::BodyKind;
pub use check::MAX_NODES;
pub use error::SceneError;
pub use format::*;
pub use resolved::Resolved;
pub use valid::ValidScene;
