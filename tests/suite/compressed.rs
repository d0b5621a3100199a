//! Compressed VTK snapshots (`vtkZLibDataCompressor`, Float32 or Float64): the layout is
//! decoded here independently of `read_vti`, and `read_vti` gives back the values within f32
//! rounding (Single) or exactly (Double).

use std::fs;
use std::io::Read;

use crate::vti::read_vti;
use flate2::read::ZlibDecoder;
use tumble::base::grid::Grid;
use tumble::io::output::{VtkField, write_vti_compressed};
use tumble::scene::Scene;
use tumble::scene::format::Precision;

use crate::common::Scratch;

/// This file's scratch directories.
fn scratch(test: &str) -> Scratch {
    Scratch::new("compressed", test)
}

fn field(grid: &Grid, f: impl Fn([usize; 3]) -> f64) -> Vec<f64> {
    let mut v = vec![0.0; grid.len()];
    for k in 0..grid.n[2] {
        for j in 0..grid.n[1] {
            for i in 0..grid.n[0] {
                v[grid.idx(i, j, k)] = f([i, j, k]);
            }
        }
    }
    v
}

/// A grid of 81,920 nodes: a 3-vector of Float32 is 983,040 bytes, several zlib blocks with
/// a partial last one.
fn grid() -> Grid {
    Grid::new([64, 64, 20], 0.1, [-1.0, 0.5, 2.0])
}

/// Values that are not representable in f32 and span many magnitudes.
fn test_fields(g: &Grid) -> [Vec<f64>; 4] {
    [
        field(g, |[i, j, k]| {
            ((i as f64) * 0.37).sin() * ((j + k) as f64 / 3.0).cos()
        }),
        field(g, |[i, j, k]| {
            1.0 / 3.0 + (i + 64 * j + 4096 * k) as f64 * 1e-3
        }),
        field(g, |[i, _, k]| {
            -1e-7 * (i as f64 + 0.1) * (k as f64 + 1.0 / 7.0)
        }),
        field(g, |[_, j, _]| 1e5 * (j as f64 + 0.1).ln()),
    ]
}

#[test]
fn single_precision_reads_back_within_f32_rounding() {
    let s = scratch("single");
    let g = grid();
    let [p, ux, uy, uz] = test_fields(&g);
    let path = s.path().join("f.vti");
    let time = 0.1 + 0.2;
    write_vti_compressed(
        &path,
        &g,
        time,
        &[
            VtkField {
                name: "p",
                components: &[&p],
            },
            VtkField {
                name: "velocity",
                components: &[&ux, &uy, &uz],
            },
        ],
        Precision::Single,
    )
    .unwrap();
    let bytes = fs::read(&path).unwrap();
    let head = String::from_utf8_lossy(&bytes[..1500]);
    assert!(
        head.contains("compressor=\"vtkZLibDataCompressor\""),
        "{head}"
    );
    assert!(head.contains("header_type=\"UInt64\""), "{head}");
    assert!(head.contains("type=\"Float32\" Name=\"p\""), "{head}");
    assert!(!head.contains("Float64\" Name=\"p\""), "{head}");

    let d = read_vti(&path).unwrap();
    assert_eq!(d.time, Some(time), "TIME stays exact");
    assert_eq!(d.whole_extent, [0, 63, 0, 63, 0, 19]);
    assert_eq!(d.arrays.len(), 2);
    assert_eq!((d.arrays[0].0.as_str(), d.arrays[0].1), ("p", 1));
    assert_eq!((d.arrays[1].0.as_str(), d.arrays[1].1), ("velocity", 3));
    // Round to nearest f32: relative error at most 2^-24, and exactly the f32 value.
    let check = |x: f64, y: f64| {
        assert!((y - x).abs() <= x.abs() * 2f64.powi(-24), "{x} read as {y}");
        assert_eq!(y, x as f32 as f64);
    };
    for (x, y) in p.iter().zip(&d.arrays[0].2) {
        check(*x, *y);
    }
    for (n, c) in [&ux, &uy, &uz].into_iter().enumerate() {
        for (i, x) in c.iter().enumerate() {
            check(*x, d.arrays[1].2[3 * i + n]);
        }
    }
}

#[test]
fn double_precision_reads_back_exactly_and_2d_vectors_get_z_zero() {
    let s = scratch("double");
    let g = Grid::new([300, 200, 1], 0.5, [1.0, -2.0, 0.0]);
    let a = field(&g, |[i, j, _]| {
        (i as f64 + 0.1) * (j as f64 + 1.0 / 3.0) - 1e-300
    });
    let b = field(&g, |[i, j, _]| (i as f64 * 1.1).sin() - j as f64 * 1e300);
    let path = s.path().join("f.vti");
    write_vti_compressed(
        &path,
        &g,
        7.0,
        &[
            VtkField {
                name: "u",
                components: &[&a, &b],
            },
            VtkField {
                name: "a",
                components: &[&a],
            },
        ],
        Precision::Double,
    )
    .unwrap();
    let d = read_vti(&path).unwrap();
    assert_eq!(d.whole_extent, [0, 299, 0, 199, 0, 0]);
    let u = &d.arrays[0].2;
    assert_eq!(u.len(), 3 * g.len());
    for i in 0..g.len() {
        assert_eq!(u[3 * i].to_bits(), a[i].to_bits());
        assert_eq!(u[3 * i + 1].to_bits(), b[i].to_bits());
        assert_eq!(u[3 * i + 2], 0.0);
    }
    assert_eq!(d.arrays[1].2, a);
}

/// The appended data of the first array, decoded by the VTK layout: `UInt64` words
/// `[nblocks, blocksize, last_blocksize, csize_0 .. csize_{n-1}]`, then the zlib blocks.
#[test]
fn appended_data_has_the_vtk_zlib_layout() {
    let s = scratch("layout");
    let g = grid();
    let [p, ..] = test_fields(&g);
    let path = s.path().join("f.vti");
    write_vti_compressed(
        &path,
        &g,
        0.0,
        &[VtkField {
            name: "p",
            components: &[&p],
        }],
        Precision::Double,
    )
    .unwrap();
    let bytes = fs::read(&path).unwrap();
    let app = bytes
        .windows(13)
        .position(|w| w == b"<AppendedData")
        .unwrap();
    let start = app + bytes[app..].iter().position(|&b| b == b'_').unwrap();
    let data = &bytes[start + 1..];
    let word = |i: usize| u64::from_le_bytes(data[8 * i..8 * i + 8].try_into().unwrap()) as usize;
    let (n, bs, last) = (word(0), word(1), word(2));
    let total = g.len() * 8;
    assert!(bs > 0);
    assert_eq!(n, total.div_ceil(bs));
    assert_eq!(last, total % bs);
    let mut pos = 8 * (3 + n);
    let mut raw = Vec::new();
    for k in 0..n {
        let len = word(3 + k);
        ZlibDecoder::new(&data[pos..pos + len])
            .read_to_end(&mut raw)
            .unwrap();
        pos += len;
    }
    assert_eq!(raw.len(), total);
    for (i, c) in raw.chunks_exact(8).enumerate() {
        assert_eq!(f64::from_le_bytes(c.try_into().unwrap()), p[i]);
    }
    assert!(
        data[pos..].starts_with(b"\n  </AppendedData>"),
        "the array ends where the header says"
    );
}

#[test]
fn constant_fields_compress_and_damage_is_an_error() {
    let s = scratch("damage");
    let g = grid();
    let c = vec![0.25; g.len()];
    let path = s.path().join("f.vti");
    let fields = [VtkField {
        name: "c",
        components: &[&c, &c, &c],
    }];
    write_vti_compressed(&path, &g, 0.0, &fields, Precision::Single).unwrap();
    let len = fs::metadata(&path).unwrap().len() as usize;
    assert!(len < g.len() * 12 / 100, "{len} bytes for a constant field");
    assert_eq!(
        read_vti(&path).unwrap().arrays[0].2,
        vec![0.25; 3 * g.len()]
    );
    // Cut the compressed data short: an error, no panic.
    let bytes = fs::read(&path).unwrap();
    fs::write(&path, &bytes[..bytes.len() - 40]).unwrap();
    assert!(read_vti(&path).is_err());
}

#[test]
fn precision_defaults_to_single_and_parses() {
    let base = "Scene(domain: (extent: [1.0, 1.0], cells: [8, 8]), numerics: (end_time: 0.1)";
    let s = Scene::parse(&format!("{base})"), "a.ron", "a").unwrap();
    assert_eq!(s.output.precision, Precision::Single);
    assert_eq!(s.output.checkpoints_kept, 2);
    let s = Scene::parse(
        &format!("{base}, output: (precision: Double, checkpoints_kept: 5))"),
        "a.ron",
        "a",
    )
    .unwrap();
    assert_eq!(s.output.precision, Precision::Double);
    assert_eq!(s.output.checkpoints_kept, 5);
    let e = Scene::parse(
        &format!("{base}, output: (checkpoints_kept: 0))"),
        "a.ron",
        "a",
    )
    .unwrap_err();
    assert!(e.to_string().contains("checkpoints_kept"), "{e}");
}
