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
//! the scene's scales), [`generate`] (body generators, expanded into bodies), [`overlap`] (bodies overlapping at the start) and [`valid`] (the
//! [`ValidScene`] that only those checks make, the only scene the engine takes).

pub mod check;
pub mod error;
pub mod format;
pub mod generate;
pub mod kappa;
mod liquid;
pub mod overlap;
pub mod valid;

pub use crate::base::params::{BodyCoupling, InterfaceAcceleration, RemeshKernel, TimeStep};
pub use crate::bodies::BodyKind;
pub use check::MAX_NODES;
pub use error::SceneError;
pub use format::*;
pub use valid::ValidScene;

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"Scene(
    domain: (extent: [2.0, 2.0], origin: [-1.0, -1.0], cells: [32, 32]),
    fluid: (
        viscosity: 0.001,
    ),
    initial: [LambOseen(center: [0.0, 0.0], circulation: 1.0, core_radius: 0.1)],
)"#;

    #[test]
    fn good_scene_loads() {
        let s = Scene::parse(GOOD, "good.ron", "good").unwrap();
        assert_eq!(s.name, "good");
        assert_eq!(s.grid().n, [32, 32, 1]);
        assert_eq!(s.grid().h, 2.0 / 32.0);
    }

    #[test]
    fn negative_viscosity_names_line_and_field() {
        let text = GOOD.replace("0.001", "-1.0");
        let e = Scene::parse(&text, "bad.ron", "bad").unwrap_err();
        assert_eq!(e.line, Some(4));
        assert_eq!(e.field.as_deref(), Some("fluid.viscosity"));
    }

    #[test]
    fn unknown_field_names_line() {
        let text = GOOD.replace("viscosity:", "viscosty:");
        let e = Scene::parse(&text, "bad.ron", "bad").unwrap_err();
        assert_eq!(e.line, Some(4));
        assert!(e.message.contains("viscosty"), "{}", e.message);
    }
}
