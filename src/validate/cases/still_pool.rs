//! `still-pool`: a pool at rest stays at rest (issue 17's gates; a 2D tank closed by a floor and a
//! lid, static half-planes, periodic along x).

use super::common::{RATIOS, tank};
use crate::bodies::free_surface::LiquidLevelSet;
use crate::validate::{Case, Report, Row, RunTime};

/// The case: what it checks, against what, and the rows known to fail.
pub const CASE: Case = Case {
    name: "still-pool",
    description: "a pool at rest (liquid 0.5 deep under 0.5 of gas, floor and lid) stays at rest: max |u| below 1e-3 sqrt(g H) over 1000 steps, liquid volume within 0.1%",
    reference: "hydrostatics",
    full: "2D, h = 1/128, density ratios 1:10, 1:100, 1:1000",
    quick: "2D, h = 1/64, ratios 1:10, 1:100, 1:1000",
    full_time: RunTime::Minutes,
    quick_time: RunTime::Seconds,
    run: still_pool,
    known_failures: &[],
};

/// A pool at rest stays at rest: max |u| < 1e-3 √(g H) over 1000 steps, volume within 0.1%.
pub fn still_pool(quick: bool) -> anyhow::Result<Report> {
    let mut rep = Report::new("still-pool");
    let h = if quick { 1.0 / 64.0 } else { 1.0 / 128.0 };
    let (g, depth) = (1.0, 0.5);
    for r in RATIOS {
        let scene = tank(
            "still-pool",
            1.0,
            1.0,
            h,
            1.0 / r,
            "[Below(height: 0.5)]",
            g,
            1e-3,
            1e9,
            "",
        )?;
        let mut sim = crate::validate::simulation(scene)?;
        let mut umax = 0.0f64;
        let mut drift = 0.0f64;
        for _ in 0..1000 {
            sim.step()?;
            umax = umax.max(sim.sample().max_u);
            let ls = sim.world.resource::<LiquidLevelSet>();
            drift = drift.max((ls.volume / ls.target_volume - 1.0).abs());
        }
        rep.rows.push(Row::abs(
            format!(
                "1:{r} pool, h = 1/{}: max |u| / sqrt(g H) over 1000 steps",
                1.0 / h
            ),
            0.0,
            umax / (g * depth).sqrt(),
            1e-3,
        ));
        rep.rows.push(Row::abs(
            format!("1:{r} pool: liquid volume drift over 1000 steps"),
            0.0,
            drift,
            1e-3,
        ));
    }
    Ok(rep)
}
