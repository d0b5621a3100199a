//! Per-body reference level sets on local grids.
//!
//! Each body keeps its reference signed distance `phi` (positive inside, see
//! [`crate::bodies::shapes`]) sampled once on a small grid in *body coordinates* that covers the
//! body's bounding box grown by a band. Memory therefore scales with the body's size, not with
//! the domain, and the per-query cost is one trilinear (bilinear in 2D) interpolation whatever
//! the shape (mesh and ellipsoid distances are only evaluated at construction).

use glam::DVec3;
use rayon::prelude::*;

use crate::bodies::shapes::ShapeGeometry;

/// A body's reference signed distance in body coordinates: sampled on a local grid, or kept
/// analytic for unbounded shapes.
#[derive(Clone, Debug)]
pub struct LocalLevelSet {
    repr: Repr,
    band: f64,
}

#[derive(Clone, Debug)]
enum Repr {
    /// `phi = sign * interpolate(grid)`; `sign = -1` stores the complement of a bounded shape
    /// whose distance is expensive (ellipse, ellipsoid, mesh) through the grid of its inside.
    Grid { grid: Grid, sign: f64 },
    /// Closed-form distance (half-spaces, complements of primitives).
    Analytic(ShapeGeometry),
}

#[derive(Clone, Debug)]
struct Grid {
    /// body-frame position of node (0, 0, 0)
    origin: DVec3,
    h: f64,
    inv_h: f64,
    /// nodes per axis; `n[2] == 1` in 2D
    n: [usize; 3],
    /// `values[i + n[0] * (j + n[1] * k)]` = phi at `origin + h (i, j, k)`
    values: Vec<f64>,
    /// bounds of the sampled shape grown by the band
    lo: DVec3,
    hi: DVec3,
    dim2: bool,
}

impl LocalLevelSet {
    /// Samples `geom.phi` on a local grid of spacing `h` (length) covering the body's bounds
    /// grown by `band` (length) on every side; in 2D (`dim == 2`) the grid is 2D (one z-layer
    /// at z = 0, queries ignore z). The grid is centred on the grown bounds, so it reaches at
    /// least `band` beyond the body on every side. Construction evaluates `geom.phi` once per
    /// node, in parallel over grid rows.
    ///
    /// Unbounded shapes (`geom.bounds() == None`: HalfSpace, Complement) keep the analytic
    /// geometry, except the complement of an ellipse, ellipsoid or mesh, whose distance is too
    /// expensive per query: its inner shape is sampled as above and the value negated (so far
    /// outside that grid, deep in the container's solid, phi grows like the distance to it).
    ///
    /// # Panics
    /// If `h` is not positive and finite, `band` is negative or not finite, or `dim` is
    /// neither 2 nor 3.
    pub fn new(geom: ShapeGeometry, h: f64, band: f64, dim: usize) -> Self {
        assert!(h.is_finite() && h > 0.0, "grid spacing must be positive");
        assert!(band.is_finite() && band >= 0.0, "band must be non-negative");
        assert!(dim == 2 || dim == 3, "dimension must be 2 or 3");
        let repr = if geom.is_bounded() {
            Repr::Grid {
                grid: Grid::sample(&geom, h, band, dim == 2),
                sign: 1.0,
            }
        } else {
            match geom.complement_inner() {
                Some(inner) if inner.is_bounded() && inner.is_expensive() => Repr::Grid {
                    grid: Grid::sample(&inner, h, band, dim == 2),
                    sign: -1.0,
                },
                _ => Repr::Analytic(geom),
            }
        };
        LocalLevelSet { repr, band }
    }

    /// phi at a body-frame point (positive inside the body). Inside the local grid: trilinear
    /// (bilinear in 2D) interpolation of the sampled signed distance. Outside it:
    /// `phi(p) = phi(clamp(p)) - dist(p, grid box)`, where `clamp(p)` is the closest point of
    /// the grid box; this is continuous, 1-Lipschitz, and `<= -band` (up to the interpolation
    /// error) since the true distance is `<= -band` on the grid box. Analytic shapes return
    /// their exact signed distance.
    #[inline]
    pub fn phi(&self, p: DVec3) -> f64 {
        match &self.repr {
            Repr::Grid { grid, sign } => sign * grid.interpolate(p),
            Repr::Analytic(g) => g.phi(p),
        }
    }

    /// Body-frame bounds of the region where `phi > -band`: the shape's bounds grown by the
    /// band (2D: `z` range `[0, 0]`). `None` for unbounded shapes (including a sampled
    /// complement).
    pub fn bounds(&self) -> Option<(DVec3, DVec3)> {
        match &self.repr {
            Repr::Grid { grid, sign } if *sign > 0.0 => Some((grid.lo, grid.hi)),
            _ => None,
        }
    }

    /// Heap and inline memory held by this level set, in bytes.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + match &self.repr {
                Repr::Grid { grid, .. } => grid.values.capacity() * std::mem::size_of::<f64>(),
                Repr::Analytic(_) => 0,
            }
    }

    /// The band (length) this level set was built with.
    pub fn band(&self) -> f64 {
        self.band
    }
    /// phi and its gradient at a body-frame point: the exact gradient of the interpolant for a
    /// sampled level set (one interpolation instead of seven for a central difference), a
    /// narrow central difference (step `delta`, length) for an analytic one.
    #[inline]
    pub fn phi_grad(&self, p: DVec3, delta: f64, dim: usize) -> (f64, DVec3) {
        match &self.repr {
            Repr::Grid { grid, sign } => {
                let (v, g) = grid.interpolate_grad(p);
                (sign * v, *sign * g)
            }
            Repr::Analytic(geom) => {
                let mut g = DVec3::ZERO;
                for ax in 0..dim {
                    let mut e = DVec3::ZERO;
                    e[ax] = delta;
                    g[ax] = (geom.phi(p + e) - geom.phi(p - e)) / (2.0 * delta);
                }
                (geom.phi(p), g)
            }
        }
    }

    /// Whether phi is interpolated from a local grid (as opposed to analytic).
    pub fn is_sampled(&self) -> bool {
        matches!(self.repr, Repr::Grid { .. })
    }

    /// Local grid nodes per axis (`[nx, ny, 1]` in 2D), `None` if analytic.
    pub fn dims(&self) -> Option<[usize; 3]> {
        match &self.repr {
            Repr::Grid { grid, .. } => Some(grid.n),
            Repr::Analytic(_) => None,
        }
    }
}

impl Grid {
    fn sample(geom: &ShapeGeometry, h: f64, band: f64, dim2: bool) -> Grid {
        let (blo, bhi) = geom.bounds().expect("sampled shapes are bounded");
        let mut lo = blo - DVec3::splat(band);
        let mut hi = bhi + DVec3::splat(band);
        if dim2 {
            lo.z = 0.0;
            hi.z = 0.0;
        }
        let centre = 0.5 * (lo + hi);
        let mut n = [1usize; 3];
        let mut origin = DVec3::ZERO;
        let axes = if dim2 { 2 } else { 3 };
        for a in 0..axes {
            // enough nodes to reach lo and hi, at least 2 (one cell) per axis
            let cells = ((hi[a] - lo[a]) / h * (1.0 - 1e-12)).ceil().max(1.0);
            n[a] = cells as usize + 1;
            origin[a] = centre[a] - 0.5 * cells * h;
        }
        let mut values = vec![0.0; n[0] * n[1] * n[2]];
        let nx = n[0];
        values
            .par_chunks_mut(nx)
            .enumerate()
            .for_each(|(row, out)| {
                let j = row % n[1];
                let k = row / n[1];
                for (i, v) in out.iter_mut().enumerate() {
                    let p = origin + h * DVec3::new(i as f64, j as f64, k as f64);
                    *v = geom.phi(p);
                }
            });
        Grid {
            origin,
            h,
            inv_h: 1.0 / h,
            n,
            values,
            lo,
            hi,
            dim2,
        }
    }

    /// `interpolate` and its gradient (piecewise: the gradient of the trilinear interpolant
    /// inside the grid box, of the distance term outside).
    #[inline]
    fn interpolate_grad(&self, p: DVec3) -> (f64, DVec3) {
        let q = (p - self.origin) * self.inv_h;
        let [nx, ny, nz] = self.n;
        let qx = q.x.clamp(0.0, (nx - 1) as f64);
        let qy = q.y.clamp(0.0, (ny - 1) as f64);
        let i = (qx as usize).min(nx - 2);
        let j = (qy as usize).min(ny - 2);
        let fx = qx - i as f64;
        let fy = qy - j as f64;
        let (dx, dy) = (q.x - qx, q.y - qy);
        let v = &self.values;
        // Inside along an axis the interpolant varies; where p is clamped it does not, and the
        // distance term takes over.
        let (inx, iny) = ((dx == 0.0) as u8 as f64, (dy == 0.0) as u8 as f64);
        if self.dim2 {
            let b = i + nx * j;
            let (a00, a10, a01, a11) = (v[b], v[b + 1], v[b + nx], v[b + nx + 1]);
            let v0 = a00 + fx * (a10 - a00);
            let v1 = a01 + fx * (a11 - a01);
            let val = v0 + fy * (v1 - v0);
            let gx = (a10 - a00) + fy * ((a11 - a01) - (a10 - a00));
            let gy = v1 - v0;
            let r = (dx * dx + dy * dy).sqrt();
            // The distance term r h (r in cells) has the gradient (dx, dy)/r per unit length.
            let mut g = DVec3::new(gx * inx, gy * iny, 0.0) * self.inv_h;
            if r > 0.0 {
                g -= DVec3::new(dx, dy, 0.0) / r;
            }
            (val - r * self.h, g)
        } else {
            let qz = q.z.clamp(0.0, (nz - 1) as f64);
            let k = (qz as usize).min(nz - 2);
            let fz = qz - k as f64;
            let dz = q.z - qz;
            let inz = (dz == 0.0) as u8 as f64;
            let sxy = nx * ny;
            let b = i + nx * (j + ny * k);
            let lerp = |a: f64, c: f64, t: f64| a + t * (c - a);
            let (v000, v100) = (v[b], v[b + 1]);
            let (v010, v110) = (v[b + nx], v[b + nx + 1]);
            let (v001, v101) = (v[b + sxy], v[b + sxy + 1]);
            let (v011, v111) = (v[b + sxy + nx], v[b + sxy + nx + 1]);
            let c00 = lerp(v000, v100, fx);
            let c10 = lerp(v010, v110, fx);
            let c01 = lerp(v001, v101, fx);
            let c11 = lerp(v011, v111, fx);
            let c0 = lerp(c00, c10, fy);
            let c1 = lerp(c01, c11, fy);
            let val = lerp(c0, c1, fz);
            // d/dfx: the x-differences, blended in y and z.
            let e00 = v100 - v000;
            let e10 = v110 - v010;
            let e01 = v101 - v001;
            let e11 = v111 - v011;
            let gx = lerp(lerp(e00, e10, fy), lerp(e01, e11, fy), fz);
            let gy = lerp(c10 - c00, c11 - c01, fz);
            let gz = c1 - c0;
            let r = (dx * dx + dy * dy + dz * dz).sqrt();
            let mut g = DVec3::new(gx * inx, gy * iny, gz * inz) * self.inv_h;
            if r > 0.0 {
                g -= DVec3::new(dx, dy, dz) / r;
            }
            (val - r * self.h, g)
        }
    }

    #[inline]
    fn interpolate(&self, p: DVec3) -> f64 {
        let q = (p - self.origin) * self.inv_h;
        let [nx, ny, nz] = self.n;
        let qx = q.x.clamp(0.0, (nx - 1) as f64);
        let qy = q.y.clamp(0.0, (ny - 1) as f64);
        let i = (qx as usize).min(nx - 2);
        let j = (qy as usize).min(ny - 2);
        let fx = qx - i as f64;
        let fy = qy - j as f64;
        let (dx, dy) = (q.x - qx, q.y - qy);
        let v = &self.values;
        if self.dim2 {
            let b = i + nx * j;
            let v0 = v[b] + fx * (v[b + 1] - v[b]);
            let v1 = v[b + nx] + fx * (v[b + nx + 1] - v[b + nx]);
            let out = (dx * dx + dy * dy).sqrt() * self.h;
            v0 + fy * (v1 - v0) - out
        } else {
            let qz = q.z.clamp(0.0, (nz - 1) as f64);
            let k = (qz as usize).min(nz - 2);
            let fz = qz - k as f64;
            let dz = q.z - qz;
            let sxy = nx * ny;
            let b = i + nx * (j + ny * k);
            let lerp = |a: f64, c: f64, t: f64| a + t * (c - a);
            let c00 = lerp(v[b], v[b + 1], fx);
            let c10 = lerp(v[b + nx], v[b + nx + 1], fx);
            let c01 = lerp(v[b + sxy], v[b + sxy + 1], fx);
            let c11 = lerp(v[b + sxy + nx], v[b + sxy + nx + 1], fx);
            let c0 = lerp(c00, c10, fy);
            let c1 = lerp(c01, c11, fy);
            let out = (dx * dx + dy * dy + dz * dz).sqrt() * self.h;
            lerp(c0, c1, fz) - out
        }
    }
}
