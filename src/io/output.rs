//! Output: ParaView files (VTK XML ImageData `.vti` snapshots and a `.pvd` time series),
//! CSV time series, and peak-memory reporting.
//!
//! Every file that must never be seen half-written (snapshots, the `.pvd` index) goes
//! through [`atomic_write_with`]: it is written to a temporary file in the same directory,
//! fsynced and renamed over the target, so a run killed at any moment leaves either the old
//! or the new file, never a torn one. The `.pvd` is rewritten after each snapshot is
//! complete, so it only ever lists complete snapshots.

use std::fmt::Write as _;
use std::fs::{self, File};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::base::grid::Grid;
use crate::scene::format::Precision;
use flate2::Compression;
use flate2::write::ZlibEncoder;
use rayon::prelude::*;

/// Buffer size for streamed output files.
const BUF_BYTES: usize = 1 << 20;

/// Distinguishes temporary files of concurrent atomic writes within one process.
static TMP_SEQ: AtomicU64 = AtomicU64::new(0);

fn invalid_input(msg: impl Into<String>) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, msg.into())
}

/// Atomically replaces `path` with `bytes` (see [`atomic_write_with`]).
pub fn atomic_write(path: &Path, bytes: &[u8]) -> io::Result<()> {
    atomic_write_with(path, |w| w.write_all(bytes))
}

/// Atomically replaces `path` with whatever `f` writes.
///
/// `f` streams into a buffered temporary file `.{filename}.tmp-{pid}-{seq}` in the same
/// directory as `path`; the file is then flushed, fsynced and renamed over `path` (and the
/// directory fsynced, best effort). If `f` or any later step fails, the temporary file is
/// removed and `path` is left untouched.
pub fn atomic_write_with(
    path: &Path,
    f: impl FnOnce(&mut BufWriter<File>) -> io::Result<()>,
) -> io::Result<()> {
    let tmp = temp_path(path)?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };

    let result = (|| {
        let file = File::create(&tmp)?;
        let mut w = BufWriter::with_capacity(BUF_BYTES, file);
        f(&mut w)?;
        let file = w.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        drop(file);
        fs::rename(&tmp, path)
    })();

    let result = result.map_err(|e| disk_full(path, e));
    match result {
        Ok(()) => {
            // Make the rename itself durable; not every platform/filesystem allows this.
            if let Ok(d) = File::open(dir) {
                let _ = d.sync_all();
            }
            Ok(())
        }
        Err(e) => {
            let _ = fs::remove_file(&tmp);
            Err(e)
        }
    }
}

/// The temporary name `.{filename}.tmp-{pid}-{seq}` next to `path` that an atomic write of
/// `path` goes through (unique within the process).
pub fn temp_path(path: &Path) -> io::Result<PathBuf> {
    let name = path
        .file_name()
        .ok_or_else(|| invalid_input(format!("no file name in {}", path.display())))?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let seq = TMP_SEQ.fetch_add(1, Ordering::Relaxed);
    Ok(dir.join(format!(
        ".{}.tmp-{}-{}",
        name.to_string_lossy(),
        std::process::id(),
        seq
    )))
}

/// Whether `e` says the disk (or the quota) is full.
pub fn is_disk_full(e: &io::Error) -> bool {
    // ENOSPC (28) and EDQUOT (122) on Linux.
    e.kind() == io::ErrorKind::StorageFull
        || e.kind() == io::ErrorKind::QuotaExceeded
        || matches!(e.raw_os_error(), Some(28) | Some(122))
}

/// `e` unchanged, unless it says the disk is full: then an error of the same kind saying
/// "the disk is full writing PATH", so the user learns what to free, not an errno.
pub fn disk_full(path: &Path, e: io::Error) -> io::Error {
    if is_disk_full(&e) && !e.to_string().starts_with("the disk is full") {
        io::Error::new(
            e.kind(),
            format!(
                "the disk is full writing {} ({e}); free some space or choose another --out",
                path.display()
            ),
        )
    } else {
        e
    }
}

/// Appends `entry` to an index's `entries` and rewrites the index with `write`; on failure the
/// entry is removed again, so the in-memory list always matches the file on disk.
pub fn push_and_write<T, S>(
    owner: &mut S,
    entries: impl Fn(&mut S) -> &mut Vec<T>,
    entry: T,
    write: impl Fn(&S) -> io::Result<()>,
) -> io::Result<()> {
    entries(owner).push(entry);
    let r = write(owner);
    if r.is_err() {
        entries(owner).pop();
    }
    r
}

/// Formats an `f64` so that parsing it back gives exactly the same value: plain decimal for
/// ordinary magnitudes, scientific notation for very large or very small ones.
pub fn fmt_f64(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 || (1e-5..1e16).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// Escapes the XML special characters of an attribute value.
fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

/// One named point field for [`write_vti`].
///
/// `components` holds 1 slice (a scalar), 2 (a 2D vector, written with z = 0 because
/// ParaView wants 3-vectors) or 3 (a 3D vector), each of `grid.len()` values in the grid's
/// flat order (x fastest).
#[derive(Clone, Copy, Debug)]
pub struct VtkField<'a> {
    pub name: &'a str,
    pub components: &'a [&'a [f64]],
}

/// Writes a VTK XML ImageData file (`.vti`) with the given point fields and the time as a
/// `TIME` field-data value, atomically and streamed (raw little-endian appended data,
/// `UInt64` headers).
///
/// Fails with `InvalidInput` if a field has 0 or more than 3 components or a component's
/// length is not `grid.len()`.
pub fn write_vti(path: &Path, grid: &Grid, time: f64, fields: &[VtkField]) -> io::Result<()> {
    check_fields(grid, fields)?;
    let npts = grid.len();
    let out_comps = |f: &VtkField| if f.components.len() == 1 { 1 } else { 3 };
    let mut offsets = Vec::with_capacity(fields.len());
    let mut offset: u64 = 0;
    for f in fields {
        offsets.push(offset);
        offset += 8 + (npts * out_comps(f) * 8) as u64;
    }
    let head = vti_head(grid, time, fields, "Float64", &offsets, false);

    atomic_write_with(path, |w| {
        w.write_all(head.as_bytes())?;
        // Values are staged in a small reusable chunk so the BufWriter sees few large writes.
        let mut chunk: Vec<u8> = Vec::with_capacity(1 << 16);
        for f in fields {
            let nc = out_comps(f);
            let bytes = (npts * nc * 8) as u64;
            w.write_all(&bytes.to_le_bytes())?;
            let comps = f.components;
            for p in 0..npts {
                match comps.len() {
                    1 => chunk.extend_from_slice(&comps[0][p].to_le_bytes()),
                    2 => {
                        chunk.extend_from_slice(&comps[0][p].to_le_bytes());
                        chunk.extend_from_slice(&comps[1][p].to_le_bytes());
                        chunk.extend_from_slice(&0.0f64.to_le_bytes());
                    }
                    _ => {
                        chunk.extend_from_slice(&comps[0][p].to_le_bytes());
                        chunk.extend_from_slice(&comps[1][p].to_le_bytes());
                        chunk.extend_from_slice(&comps[2][p].to_le_bytes());
                    }
                }
                if chunk.len() + 24 > chunk.capacity() {
                    w.write_all(&chunk)?;
                    chunk.clear();
                }
            }
            w.write_all(&chunk)?;
            chunk.clear();
        }
        w.write_all(b"\n  </AppendedData>\n</VTKFile>\n")
    })
}

/// Uncompressed bytes per zlib block of a compressed `.vti` array.
const ZLIB_BLOCK: usize = 1 << 18;

/// The values of `f` as the bytes of its appended array (interleaved per point, 2D vectors
/// padded with z = 0), little-endian, in `precision`.
fn field_bytes(f: &VtkField, npts: usize, precision: Precision) -> Vec<u8> {
    let nc = if f.components.len() == 1 { 1 } else { 3 };
    let mut out = Vec::with_capacity(npts * nc * precision.bytes());
    let mut push = |x: f64| match precision {
        Precision::Single => out.extend_from_slice(&(x as f32).to_le_bytes()),
        Precision::Double => out.extend_from_slice(&x.to_le_bytes()),
    };
    for p in 0..npts {
        for c in 0..nc {
            push(f.components.get(c).map_or(0.0, |v| v[p]));
        }
    }
    out
}

/// `raw` as a VTK zlib-compressed array: the `UInt64` header `[nblocks, blocksize,
/// last_blocksize, compressed sizes...]` followed by the zlib streams of the blocks
/// (`last_blocksize` is the size of a partial last block, 0 when every block is full).
fn zlib_array(raw: &[u8]) -> io::Result<Vec<u8>> {
    let blocks: Vec<Vec<u8>> = raw
        .par_chunks(ZLIB_BLOCK)
        .map(|b| {
            let mut e = ZlibEncoder::new(Vec::with_capacity(b.len() / 2), Compression::new(6));
            e.write_all(b)?;
            e.finish()
        })
        .collect::<io::Result<_>>()?;
    let mut out =
        Vec::with_capacity(8 * (3 + blocks.len()) + blocks.iter().map(Vec::len).sum::<usize>());
    for h in [
        blocks.len() as u64,
        ZLIB_BLOCK as u64,
        (raw.len() % ZLIB_BLOCK) as u64,
    ] {
        out.extend_from_slice(&h.to_le_bytes());
    }
    for b in &blocks {
        out.extend_from_slice(&(b.len() as u64).to_le_bytes());
    }
    for b in &blocks {
        out.extend_from_slice(b);
    }
    Ok(out)
}

/// Writes a VTK XML ImageData file (`.vti`) like [`write_vti`], with the arrays in
/// `precision` (`Float32` or `Float64`) and the appended data zlib-compressed in the format
/// of VTK's `vtkZLibDataCompressor` (what ParaView reads). The compression runs in parallel
/// over blocks; the arrays are compressed in memory before the file is written atomically.
pub fn write_vti_compressed(
    path: &Path,
    grid: &Grid,
    time: f64,
    fields: &[VtkField],
    precision: Precision,
) -> io::Result<()> {
    check_fields(grid, fields)?;
    let npts = grid.len();
    let arrays: Vec<Vec<u8>> = fields
        .iter()
        .map(|f| zlib_array(&field_bytes(f, npts, precision)))
        .collect::<io::Result<_>>()?;
    let ty = vtk_type(precision);
    let mut offsets = Vec::with_capacity(arrays.len());
    let mut offset = 0u64;
    for a in &arrays {
        offsets.push(offset);
        offset += a.len() as u64;
    }
    let head = vti_head(grid, time, fields, ty, &offsets, true);
    atomic_write_with(path, |w| {
        w.write_all(head.as_bytes())?;
        for a in &arrays {
            w.write_all(a)?;
        }
        w.write_all(b"\n  </AppendedData>\n</VTKFile>\n")
    })
}

/// Fails with `InvalidInput` if a field has 0 or more than 3 components or a component's
/// length is not `grid.len()`.
fn check_fields(grid: &Grid, fields: &[VtkField]) -> io::Result<()> {
    let npts = grid.len();
    for f in fields {
        let nc = f.components.len();
        if !(1..=3).contains(&nc) {
            return Err(invalid_input(format!(
                "field {:?} has {nc} components (1, 2 or 3 allowed)",
                f.name
            )));
        }
        for (c, comp) in f.components.iter().enumerate() {
            if comp.len() != npts {
                return Err(invalid_input(format!(
                    "field {:?} component {c} has {} values, grid has {npts} nodes",
                    f.name,
                    comp.len()
                )));
            }
        }
    }
    Ok(())
}

/// VTK's name of the arrays' type in `precision`.
fn vtk_type(precision: Precision) -> &'static str {
    match precision {
        Precision::Single => "Float32",
        Precision::Double => "Float64",
    }
}

/// The attributes naming a dataset's active arrays: its first scalar and its first vector.
fn active_arrays(fields: &[VtkField]) -> String {
    let mut a = String::new();
    if let Some(f) = fields.iter().find(|f| f.components.len() == 1) {
        let _ = write!(a, " Scalars=\"{}\"", xml_escape(f.name));
    }
    if let Some(f) = fields.iter().find(|f| f.components.len() > 1) {
        let _ = write!(a, " Vectors=\"{}\"", xml_escape(f.name));
    }
    a
}

/// The whole grid's extent and `grid`'s (a slab's planes, [`Grid::slab`], are a piece of the
/// whole), as VTK writes them: "i0 i1 j0 j1 k0 k1", inclusive node indices.
pub fn extents(grid: &Grid) -> (String, String) {
    let [nx, ny, nz] = grid.n;
    let (k0, k1, kw) = if grid.dim == 3 {
        (grid.k0, grid.k0 + nz - 1, grid.nz_whole - 1)
    } else {
        (0, 0, 0)
    };
    let xy = format!("0 {} 0 {}", nx.saturating_sub(1), ny.saturating_sub(1));
    (format!("{xy} 0 {kw}"), format!("{xy} {k0} {k1}"))
}

/// The XML of a `.vti` file up to the `_` that starts the appended data: arrays of type `ty`
/// at `offsets`, with the zlib compressor named when `compressed`.
fn vti_head(
    grid: &Grid,
    time: f64,
    fields: &[VtkField],
    ty: &str,
    offsets: &[u64],
    compressed: bool,
) -> String {
    let out_comps = |f: &VtkField| if f.components.len() == 1 { 1 } else { 3 };
    let (whole_extent, extent) = extents(grid);
    let oz = if grid.dim == 3 { grid.origin[2] } else { 0.0 };
    let h = fmt_f64(grid.h);

    let mut head = String::new();
    head.push_str("<?xml version=\"1.0\"?>\n");
    head.push_str(
        "<VTKFile type=\"ImageData\" version=\"1.0\" byte_order=\"LittleEndian\" \
         header_type=\"UInt64\"",
    );
    if compressed {
        head.push_str(" compressor=\"vtkZLibDataCompressor\"");
    }
    head.push_str(">\n");
    let _ = writeln!(
        head,
        "  <ImageData WholeExtent=\"{whole_extent}\" Origin=\"{} {} {}\" Spacing=\"{h} {h} {h}\">",
        fmt_f64(grid.origin[0]),
        fmt_f64(grid.origin[1]),
        fmt_f64(oz)
    );
    head.push_str("    <FieldData>\n");
    let _ = writeln!(
        head,
        "      <DataArray type=\"Float64\" Name=\"TIME\" NumberOfTuples=\"1\" \
         format=\"ascii\">{}</DataArray>",
        fmt_f64(time)
    );
    head.push_str("    </FieldData>\n");
    let _ = writeln!(head, "    <Piece Extent=\"{extent}\">");
    let _ = writeln!(head, "      <PointData{}>", active_arrays(fields));
    for (f, offset) in fields.iter().zip(offsets) {
        let nc = out_comps(f);
        let _ = writeln!(
            head,
            "        <DataArray type=\"{ty}\" Name=\"{}\" NumberOfComponents=\"{nc}\" \
             format=\"appended\" offset=\"{offset}\"/>",
            xml_escape(f.name)
        );
    }
    head.push_str("      </PointData>\n");
    head.push_str("      <CellData>\n      </CellData>\n");
    head.push_str("    </Piece>\n");
    head.push_str("  </ImageData>\n");
    head.push_str("  <AppendedData encoding=\"raw\">\n   _");
    head
}

/// Writes the index of a dataset written in pieces (`.pvti`, VTK's parallel ImageData): the
/// whole grid, the arrays of `fields` (as [`write_vti_compressed`] writes them in
/// `precision`), and each piece's extent and file (relative to the index's directory).
pub fn write_pvti(
    path: &Path,
    whole: &Grid,
    fields: &[VtkField],
    precision: Precision,
    pieces: &[(String, String)],
) -> io::Result<()> {
    let ty = vtk_type(precision);
    let out_comps = |f: &VtkField| if f.components.len() == 1 { 1 } else { 3 };
    let (whole_extent, _) = extents(whole);
    let h = fmt_f64(whole.h);
    let mut x = String::new();
    x.push_str("<?xml version=\"1.0\"?>\n");
    x.push_str(
        "<VTKFile type=\"PImageData\" version=\"1.0\" byte_order=\"LittleEndian\" \
         header_type=\"UInt64\">\n",
    );
    let _ = writeln!(
        x,
        "  <PImageData WholeExtent=\"{whole_extent}\" GhostLevel=\"0\" Origin=\"{} {} {}\" \
         Spacing=\"{h} {h} {h}\">",
        fmt_f64(whole.origin[0]),
        fmt_f64(whole.origin[1]),
        fmt_f64(if whole.dim == 3 { whole.origin[2] } else { 0.0 })
    );
    let _ = writeln!(x, "    <PPointData{}>", active_arrays(fields));
    for f in fields {
        let _ = writeln!(
            x,
            "      <PDataArray type=\"{ty}\" Name=\"{}\" NumberOfComponents=\"{}\"/>",
            xml_escape(f.name),
            out_comps(f)
        );
    }
    x.push_str("    </PPointData>\n");
    for (extent, file) in pieces {
        let _ = writeln!(
            x,
            "    <Piece Extent=\"{extent}\" Source=\"{}\"/>",
            xml_escape(file)
        );
    }
    x.push_str("  </PImageData>\n</VTKFile>\n");
    atomic_write(path, x.as_bytes())
}

/// A ParaView `.pvd` collection indexing a time series of snapshot files.
///
/// Each [`push`](PvdSeries::push) rewrites the whole file atomically, so call it only after
/// the snapshot it names has been written completely.
#[derive(Clone, Debug)]
pub struct PvdSeries {
    path: PathBuf,
    entries: Vec<(f64, String)>,
}

impl PvdSeries {
    /// A series written to `path` (nothing is written until the first `push`).
    pub fn new(path: impl Into<PathBuf>) -> Self {
        PvdSeries {
            path: path.into(),
            entries: Vec::new(),
        }
    }

    /// The `.pvd` file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// `(time, file name)` of every listed snapshot, in push order.
    pub fn entries(&self) -> &[(f64, String)] {
        &self.entries
    }

    /// A series written to `path` that already lists `entries` (a restarted run's; nothing
    /// is written until [`write`](PvdSeries::write) or the next `push`).
    pub fn with_entries(path: impl Into<PathBuf>, entries: Vec<(f64, String)>) -> Self {
        PvdSeries {
            path: path.into(),
            entries,
        }
    }

    /// Adds a snapshot (`file_name` relative to the `.pvd`'s directory) and rewrites the
    /// `.pvd` atomically. On failure the entry is not kept, so the in-memory list matches
    /// the file on disk.
    pub fn push(&mut self, time: f64, file_name: &str) -> io::Result<()> {
        let entry = (time, file_name.to_string());
        push_and_write(self, |s| &mut s.entries, entry, Self::write)
    }

    /// Rewrites the `.pvd` atomically with the listed snapshots.
    pub fn write(&self) -> io::Result<()> {
        let mut s = String::new();
        s.push_str("<?xml version=\"1.0\"?>\n");
        s.push_str(
            "<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\" \
             header_type=\"UInt64\">\n",
        );
        s.push_str("  <Collection>\n");
        for (t, f) in &self.entries {
            let _ = writeln!(
                s,
                "    <DataSet timestep=\"{}\" part=\"0\" file=\"{}\"/>",
                fmt_f64(*t),
                xml_escape(f)
            );
        }
        s.push_str("  </Collection>\n</VTKFile>\n");
        atomic_write(&self.path, s.as_bytes())
    }
}

/// The one CSV dialect every file tumble writes uses: RFC 4180 through the `csv` crate, `\n`
/// line ends, a field quoted only if it needs it (a comma, a double quote or a line break,
/// as a body name may have; numbers never do), no header of its own (the caller writes it).
pub fn csv_writer<W: Write>(w: W) -> csv::Writer<W> {
    csv::WriterBuilder::new()
        .has_headers(false)
        .terminator(csv::Terminator::Any(b'\n'))
        .from_writer(w)
}

/// The I/O error inside a `csv` crate error (the only kind a writer of records of one length
/// returns), else the error as `Other`.
fn csv_io(e: csv::Error) -> io::Error {
    if !e.is_io_error() {
        return io::Error::other(e);
    }
    match e.into_kind() {
        csv::ErrorKind::Io(e) => e,
        _ => unreachable!("is_io_error"),
    }
}

/// A CSV time series ([`csv_writer`]): a header line, then one row per call to
/// [`row`](CsvWriter::row) (numbers, flushed to the OS after every row) or
/// [`record`](CsvWriter::record) (text fields such as body names, quoted as needed, flushed
/// by [`flush`](CsvWriter::flush)).
#[derive(Debug)]
pub struct CsvWriter {
    w: csv::Writer<File>,
    columns: usize,
    path: PathBuf,
}

impl CsvWriter {
    /// Creates (truncates) `path` and writes the `header`.
    pub fn create(path: &Path, header: &[&str]) -> io::Result<Self> {
        let start = || {
            let mut w = csv_writer(File::create(path)?);
            w.write_record(header).map_err(csv_io)?;
            w.flush()?;
            Ok(w)
        };
        Ok(CsvWriter {
            w: start().map_err(|e| disk_full(path, e))?,
            columns: header.len(),
            path: path.to_path_buf(),
        })
    }

    /// Opens an existing CSV file of `columns` columns to append rows after its last line (a
    /// restarted run continuing its time series).
    pub fn append(path: &Path, columns: usize) -> io::Result<Self> {
        let file = fs::OpenOptions::new().append(true).open(path)?;
        Ok(CsvWriter {
            w: csv_writer(file),
            columns,
            path: path.to_path_buf(),
        })
    }

    /// Appends one row of numbers, written as [`fmt_f64`] prints them (they parse back
    /// exactly), and flushes it. Fails with `InvalidInput` if the number of values differs
    /// from the number of header columns.
    pub fn row(&mut self, values: &[f64]) -> io::Result<()> {
        self.record(values.iter().map(|v| fmt_f64(*v)))?;
        self.flush()
    }

    /// Appends one row of text fields (numbers formatted by the caller, names quoted as
    /// needed); buffered until [`flush`](CsvWriter::flush). Fails with `InvalidInput` if the
    /// number of fields differs from the number of header columns.
    pub fn record<I, T>(&mut self, fields: I) -> io::Result<()>
    where
        I: IntoIterator<Item = T>,
        T: AsRef<[u8]>,
    {
        let mut r = csv::ByteRecord::with_capacity(self.columns * 24, self.columns);
        r.extend(fields);
        if r.len() != self.columns {
            return Err(invalid_input(format!(
                "CSV row has {} values, header has {} columns",
                r.len(),
                self.columns
            )));
        }
        self.w
            .write_byte_record(&r)
            .map_err(|e| disk_full(&self.path, csv_io(e)))
    }

    /// Flushes buffered output to the OS.
    pub fn flush(&mut self) -> io::Result<()> {
        self.w.flush().map_err(|e| disk_full(&self.path, e))
    }
}

/// Peak resident set size of this process (`VmHWM` in `/proc/self/status`), in bytes;
/// `None` where that is unavailable (non-Linux).
pub fn peak_memory_bytes() -> Option<u64> {
    let status = fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let mut it = line["VmHWM:".len()..].split_whitespace();
    let value: u64 = it.next()?.parse().ok()?;
    let mult = match it.next() {
        Some("kB") | Some("KB") | Some("kb") => 1024,
        Some("mB") | Some("MB") => 1024 * 1024,
        Some("B") | None => 1,
        _ => return None,
    };
    Some(value * mult)
}
