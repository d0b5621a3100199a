//! Slice images of a run, `slices/slice_NNNNNN.png`, one per snapshot of a run with a free
//! surface or with dynamic bodies: a vertical slice through the flow that a person can page
//! through.
//!
//! In 3D the slice is the x–z plane (z up) through the grid nodes nearest the centre of the
//! first dynamic body (lowest id), else through the middle of the box; in 2D it is the whole
//! x–y plane (y up). The colour is the vorticity component normal to the slice (ω_y in 3D, ω
//! in 2D) on a blue–white–red scale symmetric about 0, whose end is the 99th percentile of
//! |value| over the slice's nodes outside the bodies (larger values saturate; the colour bar
//! beside the slice gives the end); the inside of the bodies is shaded grey, the free surface's zero
//! level (φ_w = 0) is a black line and the bodies' (the union level set φ = 0) a green one.
//! The title names the scene, the time and where the slice is.
//!
//! Each grid node is a block of [`pixels_per_cell`] × [`pixels_per_cell`] pixels (2 to 4);
//! the pixels are drawn straight into an RGB buffer, the text through `plotters` with the
//! bundled font, and the PNG is encoded by the `image` crate's encoder (the one `plotters`
//! brings in) and written atomically.

use crate::base::grid::Grid;
use crate::bodies::free_surface::LiquidLevelSet;
use crate::bodies::{Body, RigidState};
use crate::io::isosurface::contour;
use crate::io::output::atomic_write;
use crate::io::plot::{FAMILY, register_bundled_font};
use crate::scene::BodyKind;
use crate::sim::engine::Simulation;
use anyhow::{Context, Result, anyhow};
use plotters::prelude::*;
use std::path::Path;

/// The subdirectory of the run directory that holds the slice images.
pub const SLICE_DIR: &str = "slices";

/// Height of the band above the slice that holds the title and the legend, pixels.
const TITLE_BAND: u32 = 44;
/// Width of the band right of the slice that holds the colour bar, pixels.
const BAR_BAND: u32 = 110;
/// The slice area is at least this high (small grids), pixels.
const MIN_HEIGHT: u32 = 220;

/// What one slice image shows: values at the grid's nodes.
pub struct SliceInput<'a> {
    /// The grid the fields live on.
    pub grid: &'a Grid,
    /// The colour: the vorticity component normal to the slice, one value per node.
    pub colour: &'a [f64],
    /// What the colour is, for the legend (e.g. "ω_y").
    pub colour_name: &'a str,
    /// The free surface's level set φ_w (> 0 in the liquid), one value per node, if any.
    pub liquid: Option<&'a [f64]>,
    /// The bodies' union level set φ (> 0 inside a body), one value per node, if any.
    pub bodies: Option<&'a [f64]>,
    /// In 3D, the y index of the x–z plane shown (taken modulo the grid); ignored in 2D.
    pub j: usize,
    /// The title line.
    pub title: &'a str,
}

/// Pixels per grid cell along each axis: about 768 pixels for the longer side, 2 to 4.
pub fn pixels_per_cell(grid: &Grid) -> u32 {
    let [nx, nv] = slice_dims(grid);
    (768 / nx.max(nv).max(1)).clamp(2, 4) as u32
}

/// The slice's node counts: horizontal (x) and vertical (z in 3D, y in 2D).
fn slice_dims(grid: &Grid) -> [usize; 2] {
    if grid.dim == 3 {
        [grid.n[0], grid.n[2]]
    } else {
        [grid.n[0], grid.n[1]]
    }
}

/// The size of a slice image of `grid`, (width, height) in pixels: the slice at
/// [`pixels_per_cell`] (at least 220 pixels high), a 110-pixel colour-bar band on the right
/// and a 44-pixel title band on top.
pub fn slice_size(grid: &Grid) -> (u32, u32) {
    let s = pixels_per_cell(grid);
    let [nx, nv] = slice_dims(grid);
    let (w, h) = (nx as u32 * s, (nv as u32 * s).max(MIN_HEIGHT));
    (w + BAR_BAND, h + TITLE_BAND)
}

/// The blue–white–red colour of `t` in [-1, 1] (ParaView's "Cool to Warm" anchors).
fn colour_map(t: f64) -> [u8; 3] {
    const ANCHORS: [[f64; 3]; 5] = [
        [59.0, 76.0, 192.0],
        [141.0, 176.0, 254.0],
        [221.0, 221.0, 221.0],
        [244.0, 154.0, 123.0],
        [180.0, 4.0, 38.0],
    ];
    if !t.is_finite() {
        return [128, 128, 128];
    }
    let x = (t.clamp(-1.0, 1.0) + 1.0) * 2.0;
    let k = (x.floor() as usize).min(3);
    let f = x - k as f64;
    let (a, b) = (ANCHORS[k], ANCHORS[k + 1]);
    [0, 1, 2].map(|c| (a[c] + f * (b[c] - a[c])).round() as u8)
}

/// An RGB image being drawn.
struct Canvas {
    w: u32,
    h: u32,
    buf: Vec<u8>,
}

impl Canvas {
    fn set(&mut self, x: i64, y: i64, c: [u8; 3]) {
        if x >= 0 && y >= 0 && (x as u32) < self.w && (y as u32) < self.h {
            let o = 3 * (y as usize * self.w as usize + x as usize);
            self.buf[o..o + 3].copy_from_slice(&c);
        }
    }

    /// A line about 2 pixels wide from `a` to `b` (pixel coordinates), clipped to `clip`
    /// (x0, y0, x1, y1).
    fn line(&mut self, a: [f64; 2], b: [f64; 2], c: [u8; 3], clip: [f64; 4]) {
        let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
        if !len.is_finite() {
            return;
        }
        let steps = (2.0 * len).ceil().max(1.0) as usize;
        for k in 0..=steps {
            let f = k as f64 / steps as f64;
            let (x, y) = (a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]));
            if x < clip[0] || y < clip[1] || x >= clip[2] || y >= clip[3] {
                continue;
            }
            let (x, y) = ((x - 0.5).floor() as i64, (y - 0.5).floor() as i64);
            for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                self.set(x + dx, y + dy, c);
            }
        }
    }
}

/// The PNG bytes of the slice image of `input`; an error if a field has not one value per
/// node or the text cannot be drawn.
pub fn render(input: &SliceInput) -> Result<Vec<u8>> {
    check_lengths(input)?;
    let nodes = SliceNodes::new(input);
    let (w, h) = slice_size(input.grid);
    let mut cv = Canvas {
        w,
        h,
        buf: vec![255; 3 * w as usize * h as usize],
    };
    let scale = colour_scale(input, &nodes);
    paint_nodes(&mut cv, input, &nodes, scale);
    draw_zero_levels(&mut cv, input, &nodes);
    let bar = ColourBar::new(&nodes, h);
    bar.paint(&mut cv);
    draw_text(&mut cv, input, &bar, scale)?;
    let mut png = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut png),
        &cv.buf,
        w,
        h,
        image::ColorType::Rgb8,
    )
    .context("cannot encode the slice image")?;
    Ok(png)
}

/// An error if a field of `input` has not one value per node, or the grid has none.
fn check_lengths(input: &SliceInput) -> Result<()> {
    let n = input.grid.len();
    let check = |name: &str, f: Option<&[f64]>| match f {
        Some(f) if f.len() != n => Err(anyhow!(
            "the slice's {name} has {} values, the grid {n} nodes",
            f.len()
        )),
        _ => Ok(()),
    };
    check("colour", Some(input.colour))?;
    check("free surface", input.liquid)?;
    check("bodies", input.bodies)?;
    anyhow::ensure!(n > 0, "the grid has no node");
    Ok(())
}

/// The nodes of a slice: `nx` along x by `nv` up, each a block of `s` × `s` pixels.
struct SliceNodes<'a> {
    grid: &'a Grid,
    nx: usize,
    nv: usize,
    /// In 3D, the y index of the plane.
    j: usize,
    /// Pixels per node along each axis.
    s: u32,
}

impl<'a> SliceNodes<'a> {
    /// The nodes of the slice `input` shows.
    fn new(input: &SliceInput<'a>) -> Self {
        let g = input.grid;
        let [nx, nv] = slice_dims(g);
        SliceNodes {
            grid: g,
            nx,
            nv,
            j: if g.dim == 3 { input.j % g.n[1] } else { 0 },
            s: pixels_per_cell(g),
        }
    }

    /// Node (i, k) of the slice: x index i, vertical index k.
    fn node(&self, i: usize, k: usize) -> usize {
        if self.grid.dim == 3 {
            self.grid.idx(i % self.nx, self.j, k % self.nv)
        } else {
            self.grid.idx(i % self.nx, k % self.nv, 0)
        }
    }
}

/// The colour scale: the 99th percentile of |value| over the slice's nodes outside the
/// bodies (a thin peak at a wall would wash out the wake), else their largest |value|.
fn colour_scale(input: &SliceInput, nodes: &SliceNodes) -> f64 {
    let (nx, nv) = (nodes.nx, nodes.nv);
    let mut mags: Vec<f64> = Vec::with_capacity(nx * nv);
    for k in 0..nv {
        for i in 0..nx {
            let id = nodes.node(i, k);
            let v = input.colour[id];
            if v.is_finite() && !input.bodies.is_some_and(|b| b[id] > 0.0) {
                mags.push(v.abs());
            }
        }
    }
    let max = mags.iter().copied().fold(0.0, f64::max);
    let mut scale = max;
    if !mags.is_empty() {
        let q = (0.99 * (mags.len() - 1) as f64) as usize;
        let (_, p, _) = mags.select_nth_unstable_by(q, f64::total_cmp);
        if *p > 0.0 {
            scale = *p;
        }
    }
    scale
}

/// Paint each node's block in its colour on the scale `scale` (shaded grey inside the
/// bodies).
fn paint_nodes(cv: &mut Canvas, input: &SliceInput, nodes: &SliceNodes, scale: f64) {
    let unit = if scale > 0.0 { scale } else { 1.0 };
    let (nx, nv, s) = (nodes.nx, nodes.nv, nodes.s);
    let top = TITLE_BAND as i64;
    let y_of = |k: usize| top + ((nv - 1 - k) as u32 * s) as i64;
    for k in 0..nv {
        for i in 0..nx {
            let id = nodes.node(i, k);
            let mut c = colour_map(input.colour[id] / unit);
            if input.bodies.is_some_and(|b| b[id] > 0.0) {
                c = c.map(|x| ((x as u32 + 90) / 2) as u8);
            }
            for dy in 0..s as i64 {
                for dx in 0..s as i64 {
                    cv.set((i as u32 * s) as i64 + dx, y_of(k) + dy, c);
                }
            }
        }
    }
}

/// The zero levels of the bodies (green) and the free surface (black): lattice point (a, b)
/// is at the centre of node (a, b)'s block.
fn draw_zero_levels(cv: &mut Canvas, input: &SliceInput, nodes: &SliceNodes) {
    let (nx, nv, s) = (nodes.nx, nodes.nv, nodes.s);
    let sf = s as f64;
    let clip = [
        0.0,
        TITLE_BAND as f64,
        (nx as u32 * s) as f64,
        (TITLE_BAND + nv as u32 * s) as f64,
    ];
    let to_px = |p: [f64; 2]| {
        [
            (p[0] + 0.5) * sf,
            TITLE_BAND as f64 + (nv as f64 - 0.5 - p[1]) * sf,
        ]
    };
    for (field, c) in [(input.bodies, [0, 140, 0]), (input.liquid, [0, 0, 0])] {
        let Some(f) = field else { continue };
        let (points, segments) = contour(nx, nv, |i, k| f[nodes.node(i, k)]);
        for [p, q] in segments {
            cv.line(
                to_px(points[p as usize]),
                to_px(points[q as usize]),
                c,
                clip,
            );
        }
    }
}

/// Where the colour bar is, pixels: its left edge, top and bottom.
struct ColourBar {
    x: i64,
    top: i64,
    bottom: i64,
}

impl ColourBar {
    /// The colour bar right of the slice of `nodes`, in an image `h` pixels high.
    fn new(nodes: &SliceNodes, h: u32) -> Self {
        let top = TITLE_BAND as i64;
        ColourBar {
            x: (nodes.nx as u32 * nodes.s + 16) as i64,
            top: top + 16,
            bottom: top + (h - TITLE_BAND) as i64 - 16,
        }
    }

    /// Paint the bar, 16 pixels wide, from +1 at the top to -1 at the bottom.
    fn paint(&self, cv: &mut Canvas) {
        let span = (self.bottom - self.top).max(1);
        for y in self.top..=self.bottom {
            let t = 1.0 - 2.0 * (y - self.top) as f64 / span as f64;
            for x in self.x..self.x + 16 {
                cv.set(x, y, colour_map(t));
            }
        }
    }
}

/// The title, the legend and the colour bar's labels (its ends at ±`scale`).
fn draw_text(cv: &mut Canvas, input: &SliceInput, bar: &ColourBar, scale: f64) -> Result<()> {
    register_bundled_font()?;
    let top = TITLE_BAND as i64;
    let root = BitMapBackend::with_buffer(&mut cv.buf, (cv.w, cv.h)).into_drawing_area();
    let err = |e: DrawingAreaErrorKind<_>| anyhow!("cannot draw the slice's text: {e}");
    let big = TextStyle::from((FAMILY, 16).into_font()).color(&BLACK);
    let small = TextStyle::from((FAMILY, 12).into_font()).color(&BLACK);
    root.draw_text(input.title, &big, (6, 4)).map_err(err)?;
    let mut legend = format!("colour: {} (normal to the slice)", input.colour_name);
    if input.liquid.is_some() {
        legend.push_str("; black: free surface");
    }
    if input.bodies.is_some() {
        legend.push_str("; green: bodies (grey inside)");
    }
    root.draw_text(&legend, &small, (6, 25)).map_err(err)?;
    let lx = (bar.x + 20) as i32;
    let mid = ((bar.top + bar.bottom) / 2) as i32;
    for (text, y) in [
        (format!("+{scale:.3e}"), bar.top as i32 - 6),
        ("0".to_string(), mid - 6),
        (format!("-{scale:.3e}"), bar.bottom as i32 - 6),
    ] {
        root.draw_text(&text, &small, (lx, y)).map_err(err)?;
    }
    root.draw_text(input.colour_name, &small, (bar.x as i32, top as i32))
        .map_err(err)?;
    root.present().map_err(err)?;
    Ok(())
}

/// Whether the snapshots of `sim`'s run hold slice images: it has a free surface (a
/// [`LiquidLevelSet`]) or a dynamic body.
pub fn wants_slices(sim: &Simulation) -> bool {
    sim.world.contains_resource::<LiquidLevelSet>()
        || sim
            .scene()
            .bodies
            .iter()
            .any(|b| matches!(b.kind, BodyKind::Dynamic))
}

/// The file name of slice image `index`, relative to the run directory.
pub fn slice_file(index: usize) -> String {
    format!("{SLICE_DIR}/slice_{index:06}.png")
}

/// Write slice image `index` of `sim`'s current state into the run directory `dir` (making
/// `slices/` if needed); returns its name relative to `dir`.
pub fn write_slice(dir: &Path, index: usize, sim: &Simulation) -> Result<String> {
    let g = sim.grid();
    let fl = sim.fields();
    let comp = if g.dim == 3 { 1 } else { 0 };
    let zeros;
    let colour = match fl.omega().get(comp) {
        Some(c) if c.len() == g.len() => c.as_slice(),
        _ => {
            zeros = vec![0.0; g.len()];
            &zeros
        }
    };
    let liquid = sim
        .world
        .get_resource::<LiquidLevelSet>()
        .map(|l| l.phi.as_slice())
        .filter(|p| p.len() == g.len());
    let phi_min = -crate::bodies::band(g);
    let bodies: Option<Vec<f64>> = sim
        .world
        .get_resource::<crate::bodies::BodyFields>()
        .filter(|b| b.phi.len() == g.len())
        .map(|b| b.phi.iter().map(|p| p.max(phi_min)).collect());
    // The first dynamic body's centre, else the middle of the box.
    let world = &sim.world;
    let centre = world.try_query::<(&Body, &RigidState)>().and_then(|mut q| {
        q.iter(world)
            .filter(|(b, _)| b.is_dynamic())
            .min_by_key(|(b, _)| b.id)
            .map(|(_, st)| st.center.y)
    });
    let j = match centre {
        Some(y) if y.is_finite() => g.nearest(1, y),
        _ => g.n[1] / 2,
    };
    let name = &sim.scene().name;
    let title = if g.dim == 3 {
        format!(
            "{name}   t = {:.4}   slice y = {:.4}",
            sim.time(),
            g.origin[1] + j as f64 * g.h
        )
    } else {
        format!("{name}   t = {:.4}", sim.time())
    };
    let png = render(&SliceInput {
        grid: g,
        colour,
        colour_name: if g.dim == 3 { "ω_y" } else { "ω" },
        liquid,
        bodies: bodies.as_deref(),
        j,
        title: &title,
    })?;
    let sub = dir.join(SLICE_DIR);
    std::fs::create_dir_all(&sub).with_context(|| format!("cannot create {}", sub.display()))?;
    let file = slice_file(index);
    atomic_write(&dir.join(&file), &png).with_context(|| format!("cannot write {file}"))?;
    Ok(file)
}
