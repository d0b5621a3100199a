//! A reader for the `.vti` files tumble writes, so the tests check the output rather than
//! assume it: exactly the formats `write_vti` and `write_vti_compressed` write (Float32 or
//! Float64 point arrays, raw appended data with `UInt64` little-endian headers, uncompressed or
//! zlib-compressed, `TIME` as ascii field data); values come back as `f64`. The XML before the
//! appended data is read with roxmltree.

use flate2::read::ZlibDecoder;
use std::io::{self, Read};
use std::path::Path;

/// What [`read_vti`] found in a `.vti` file.
#[derive(Clone, Debug, PartialEq)]
pub struct VtiData {
    /// `x0 x1 y0 y1 z0 z1` (inclusive node ranges).
    pub whole_extent: [usize; 6],
    pub origin: [f64; 3],
    pub spacing: [f64; 3],
    /// The `TIME` field-data value, if present.
    pub time: Option<f64>,
    /// `(name, number of components, values)` per point array, in file order; values are
    /// interleaved per point (x fastest), so `values.len() == points * components`.
    pub arrays: Vec<(String, usize, Vec<f64>)>,
}

fn bad(msg: impl Into<String>) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidData, msg.into())
}

/// Attribute `key` of element `n`.
fn attr<'a>(n: roxmltree::Node<'a, '_>, key: &str) -> io::Result<&'a str> {
    n.attribute(key)
        .ok_or_else(|| bad(format!("<{}> lacks {key}", n.tag_name().name())))
}

/// The `N` numbers of attribute `key` of `n`.
fn nums<T: std::str::FromStr, const N: usize>(
    n: roxmltree::Node<'_, '_>,
    key: &str,
) -> io::Result<[T; N]> {
    let s = attr(n, key)?;
    let v: Vec<T> = s
        .split_whitespace()
        .map(str::parse)
        .collect::<Result<_, _>>()
        .map_err(|_| bad(format!("bad {key}: {s:?}")))?;
    v.try_into()
        .map_err(|_| bad(format!("{key} needs {N} numbers: {s:?}")))
}

/// Reads the `.vti` file at `path` (see the module doc for the formats).
pub fn read_vti(path: &Path) -> io::Result<VtiData> {
    let bytes = std::fs::read(path)?;
    let find = |from: usize, what: &[u8]| {
        bytes[from..]
            .windows(what.len())
            .position(|w| w == what)
            .map(|i| from + i)
    };
    let app = find(0, b"<AppendedData").ok_or_else(|| bad("no <AppendedData>"))?;
    let tag_end = find(app, b">").ok_or_else(|| bad("unterminated <AppendedData>"))?;
    let underscore = find(tag_end, b"_").ok_or_else(|| bad("no '_' starting the appended data"))?;
    let data = &bytes[underscore + 1..];
    // The XML up to the appended data, closed: everything but the binary data.
    let head = std::str::from_utf8(&bytes[..=tag_end]).map_err(|_| bad("non-UTF-8 XML"))?;
    let xml = format!("{head}</AppendedData></VTKFile>");
    let doc = roxmltree::Document::parse(&xml).map_err(|e| bad(e.to_string()))?;
    let elements = || doc.descendants().filter(roxmltree::Node::is_element);
    let element = |name: &str| {
        elements()
            .find(|n| n.has_tag_name(name))
            .ok_or_else(|| bad(format!("no <{name}>")))
    };

    let file = doc.root_element();
    let want = [
        ("type", "ImageData"),
        ("byte_order", "LittleEndian"),
        ("header_type", "UInt64"),
    ];
    for (key, value) in want {
        if file.attribute(key) != Some(value) {
            return Err(bad(format!("VTKFile {key} is not {value}")));
        }
    }
    let compressed = match file.attribute("compressor") {
        None => false,
        Some("vtkZLibDataCompressor") => true,
        Some(c) => return Err(bad(format!("unknown compressor {c:?}"))),
    };
    if element("AppendedData")?.attribute("encoding") != Some("raw") {
        return Err(bad("AppendedData encoding is not raw"));
    }
    let image = element("ImageData")?;
    let whole_extent: [usize; 6] = nums(image, "WholeExtent")?;
    let origin = nums(image, "Origin")?;
    let spacing = nums(image, "Spacing")?;

    let in_parent = |n: &roxmltree::Node, parent: &str| {
        n.has_tag_name("DataArray") && n.parent_element().is_some_and(|p| p.has_tag_name(parent))
    };
    let time = match elements()
        .find(|n| in_parent(n, "FieldData") && n.attribute("Name") == Some("TIME"))
    {
        None => None,
        Some(n) => {
            let first = n
                .text()
                .and_then(|t| t.split_whitespace().next())
                .ok_or_else(|| bad("empty TIME array"))?;
            Some(
                first
                    .parse()
                    .map_err(|_| bad(format!("bad TIME {first:?}")))?,
            )
        }
    };

    // The points are the piece's (the whole grid's, unless the file is a piece of a `.pvti`).
    let piece_extent: [usize; 6] = nums(element("Piece")?, "Extent")?;
    let mut npts = 1usize;
    for a in 0..3 {
        let (lo, hi) = (piece_extent[2 * a], piece_extent[2 * a + 1]);
        if hi < lo || lo < whole_extent[2 * a] || hi > whole_extent[2 * a + 1] {
            return Err(bad("empty piece, or a piece outside the WholeExtent"));
        }
        npts *= hi - lo + 1;
    }
    let mut arrays = Vec::new();
    for n in elements().filter(|n| in_parent(n, "PointData")) {
        let name = attr(n, "Name")?.to_string();
        let size = match attr(n, "type")? {
            "Float64" => 8,
            "Float32" => 4,
            t => {
                return Err(bad(format!(
                    "array {name:?} is {t}, not Float32 or Float64"
                )));
            }
        };
        if attr(n, "format")? != "appended" {
            return Err(bad(format!("array {name:?} is not appended")));
        }
        let nc: usize = match n.attribute("NumberOfComponents") {
            Some(s) => s
                .trim()
                .parse()
                .map_err(|_| bad("bad NumberOfComponents"))?,
            None => 1,
        };
        let off: usize = attr(n, "offset")?
            .trim()
            .parse()
            .map_err(|_| bad("bad offset"))?;
        let expected = npts * nc * size;
        let raw = if compressed {
            inflate_array(data, off, expected).map_err(|e| bad(format!("array {name:?}: {e}")))?
        } else {
            let head = data
                .get(off..off + 8)
                .ok_or_else(|| bad(format!("array {name:?}: offset past end")))?;
            let nbytes = u64::from_le_bytes(head.try_into().unwrap()) as usize;
            if nbytes != expected {
                return Err(bad(format!(
                    "array {name:?}: {nbytes} bytes, expected {expected}"
                )));
            }
            data.get(off + 8..off + 8 + nbytes)
                .ok_or_else(|| bad(format!("array {name:?}: truncated")))?
                .to_vec()
        };
        let values = if size == 8 {
            raw.chunks_exact(8)
                .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
                .collect()
        } else {
            raw.chunks_exact(4)
                .map(|c| f32::from_le_bytes(c.try_into().unwrap()) as f64)
                .collect()
        };
        arrays.push((name, nc, values));
    }

    Ok(VtiData {
        whole_extent,
        origin,
        spacing,
        time,
        arrays,
    })
}

/// The `expected` bytes of the zlib-compressed array at `off` in the appended `data` (see
/// `zlib_array` in `src/io/output.rs` for the layout).
fn inflate_array(data: &[u8], off: usize, expected: usize) -> Result<Vec<u8>, String> {
    let word = |i: usize| -> Result<usize, String> {
        let at = off + 8 * i;
        data.get(at..at + 8)
            .map(|b| u64::from_le_bytes(b.try_into().unwrap()) as usize)
            .ok_or_else(|| "compression header past the end".to_string())
    };
    let (nblocks, bs, last) = (word(0)?, word(1)?, word(2)?);
    let total = match (nblocks, last) {
        (0, _) => 0,
        (n, 0) => n * bs,
        (n, l) => (n - 1) * bs + l,
    };
    if total != expected {
        return Err(format!("{total} bytes, expected {expected}"));
    }
    let mut pos = off + 8 * (3 + nblocks);
    let mut out = Vec::with_capacity(expected);
    for k in 0..nblocks {
        let len = word(3 + k)?;
        let block = data
            .get(pos..pos + len)
            .ok_or_else(|| "truncated compressed data".to_string())?;
        let before = out.len();
        ZlibDecoder::new(block)
            .read_to_end(&mut out)
            .map_err(|e| format!("bad zlib block {k}: {e}"))?;
        let want = if k + 1 == nblocks && last != 0 {
            last
        } else {
            bs
        };
        if out.len() - before != want {
            return Err(format!(
                "block {k} inflates to {} bytes, expected {want}",
                out.len() - before
            ));
        }
        pos += len;
    }
    Ok(out)
}
