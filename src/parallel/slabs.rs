//! The split of the grid into slabs of z-planes, and of the spectral layout into ranges of y
//! rows.

use std::ops::Range;

/// Splits `n` items over `parts` ranks as evenly as they go: the first `n % parts` ranks get one
/// more than the others. Rank `r`'s range is `split(n, parts, r)`.
pub fn split(n: usize, parts: usize, r: usize) -> Range<usize> {
    let (q, rem) = (n / parts, n % parts);
    let start = r * q + r.min(rem);
    start..start + q + usize::from(r < rem)
}

/// Why a grid cannot be split over a number of ranks.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DecompositionError {
    /// A 2D grid has one z-plane: it runs on one rank.
    #[error("a 2D grid runs on one process, not {ranks} (split a 3D box instead)")]
    TwoD { ranks: usize },
    /// Each rank holds at least `min` z-planes (the remeshing kernel's reach) and as many y rows
    /// as it holds nothing on.
    #[error(
        "{ranks} processes for {nz} z-planes and {ny} y-rows: each process needs at least {min} \
         z-planes and one y-row, so at most {max} processes can share this grid"
    )]
    TooManyRanks {
        ranks: usize,
        nz: usize,
        ny: usize,
        min: usize,
        max: usize,
    },
}

/// The slab decomposition of one grid over `ranks` processes, seen from rank `rank`.
///
/// In real space rank `r` owns the z-planes [`Slabs::planes`]`(r)`, every x and y; in the
/// spectral layout (after the x and y transforms and the transpose) it owns the y rows
/// [`Slabs::rows`]`(r)`, every x wavenumber and every z. Both splits are as even as they go
/// ([`split`]), so any rank count up to the limits of [`Slabs::new`] works.
#[derive(Debug, Clone, PartialEq)]
pub struct Slabs {
    /// The whole grid's node counts.
    pub n: [usize; 3],
    /// Number of ranks.
    pub ranks: usize,
    /// This rank.
    pub rank: usize,
}

impl Slabs {
    /// The fewest z-planes a rank may own when there are several, so that every halo comes from
    /// the two neighbouring ranks alone: the widest reach of a stencil along z. The M'4 kernel
    /// puts a particle moved by δ cells on nodes up to ⌊|δ|⌋ + 2 from where it started, 6 at
    /// the default step bound (|δ| ≤ 4, `cfl`); the stretching's eighth-order differences reach
    /// 4 (docs/scaling.md, "The slab limit").
    pub const MIN_PLANES: usize = 6;

    /// The whole grid on one process.
    pub fn single(n: [usize; 3]) -> Self {
        Slabs {
            n,
            ranks: 1,
            rank: 0,
        }
    }

    /// The split of grid `n` over `ranks` processes seen from `rank`; an error when a rank would
    /// get fewer than [`Slabs::MIN_PLANES`] planes or no y row, or the grid is 2D.
    pub fn new(n: [usize; 3], ranks: usize, rank: usize) -> Result<Self, DecompositionError> {
        assert!(ranks > 0 && rank < ranks, "slabs: rank {rank} of {ranks}");
        if ranks > 1 {
            if n[2] == 1 {
                return Err(DecompositionError::TwoD { ranks });
            }
            let max = (n[2] / Self::MIN_PLANES).min(n[1]);
            if ranks > max {
                return Err(DecompositionError::TooManyRanks {
                    ranks,
                    nz: n[2],
                    ny: n[1],
                    min: Self::MIN_PLANES,
                    max,
                });
            }
        }
        Ok(Slabs { n, ranks, rank })
    }

    /// The z-planes rank `r` owns in real space.
    pub fn planes(&self, r: usize) -> Range<usize> {
        split(self.n[2], self.ranks, r)
    }

    /// The y rows rank `r` owns in the spectral layout.
    pub fn rows(&self, r: usize) -> Range<usize> {
        split(self.n[1], self.ranks, r)
    }

    /// This rank's z-planes.
    pub fn my_planes(&self) -> Range<usize> {
        self.planes(self.rank)
    }

    /// This rank's spectral y rows.
    pub fn my_rows(&self) -> Range<usize> {
        self.rows(self.rank)
    }

    /// The rank below (z - 1, periodic) and above (z + 1).
    pub fn neighbours(&self) -> (usize, usize) {
        (
            (self.rank + self.ranks - 1) % self.ranks,
            (self.rank + 1) % self.ranks,
        )
    }
}
