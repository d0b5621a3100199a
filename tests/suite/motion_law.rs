//! Which dynamic bodies move by Newton-Euler with their own mass (`MotionLaw`): those at least
//! twice as heavy as the largest added mass their shape can have, so that the explicit update,
//! which amplifies an error by m_a / m per step, is stable. The thresholds below are the
//! analytic added masses: a sphere's is ρ_F V / 2, a disk's ρ_F A, an ellipse's broadside
//! ρ_F π a² (a the semi-axis across the motion; Lamb, Hydrodynamics, sections 71 and 92).

use std::path::Path;
use tumble::bodies::coupling::{MotionLaw, motion_law};
use tumble::bodies::levelset::LocalLevelSet;
use tumble::bodies::shapes::Shape;

fn law(shape: Shape, dim: usize, density: f64) -> MotionLaw {
    let h = 1.0 / 64.0;
    let geom = shape.build(Path::new(".")).expect("shape");
    let ls = LocalLevelSet::new(geom, h, 4.0 * h, dim);
    motion_law(&ls, h, dim, density, 1.0)
}

/// A sphere (m_a = V/2): Newton-Euler from density 1 (twice its added mass), not below.
#[test]
fn sphere_moves_by_newton_euler_from_twice_its_added_mass() {
    let s = || Shape::Sphere { radius: 0.1 };
    assert_eq!(law(s(), 3, 0.9), MotionLaw::Projected);
    assert_eq!(law(s(), 3, 1.1), MotionLaw::NewtonEuler);
    assert_eq!(law(s(), 3, 1000.0), MotionLaw::NewtonEuler);
}

/// A disk (m_a = A): from density 2.
#[test]
fn disk_moves_by_newton_euler_from_twice_its_added_mass() {
    let d = || Shape::Disk { radius: 0.1 };
    assert_eq!(law(d(), 2, 1.8), MotionLaw::Projected);
    assert_eq!(law(d(), 2, 2.2), MotionLaw::NewtonEuler);
}

/// An ellipse of aspect ratio 10 moving broadside has ten times the added mass of its own
/// fluid: at density 5 the explicit update would amplify an error twofold per step, so it
/// stays with the projection; at 50 (m_a / m = 0.2) it moves by Newton-Euler.
#[test]
fn thin_ellipse_needs_its_broadside_added_mass() {
    let e = || Shape::Ellipse { radii: [0.2, 0.02] };
    assert_eq!(law(e(), 2, 5.0), MotionLaw::Projected);
    assert_eq!(law(e(), 2, 50.0), MotionLaw::NewtonEuler);
}

/// A cube of half-side 0.1 (added mass about 0.7 of its displaced fluid; the bound from its
/// equivalent ellipsoid is 0.69, so Newton-Euler from density 1.4): at density 3, not at 0.5.
#[test]
fn cube_is_classified_by_its_shape() {
    let b = || Shape::Box {
        half_extents: [0.1, 0.1, 0.1],
    };
    assert_eq!(law(b(), 3, 0.5), MotionLaw::Projected);
    assert_eq!(law(b(), 3, 3.0), MotionLaw::NewtonEuler);
}
