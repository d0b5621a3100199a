//! The scene loader never panics: every bundled scene, mutated thousands of ways (characters
//! deleted, duplicated, swapped or inserted, text truncated, numbers replaced by -1, 0, 1e300,
//! NaN, inf, huge integers, fields renamed, brackets dropped), either loads or is rejected with
//! a message that names the file.

use std::path::{Path, PathBuf};
use tumble::scene::Scene;

/// Cases in all, spread over the bundled scenes.
const CASES: usize = 3000;

/// xorshift64*: small, deterministic.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

const NUMBERS: &[&str] = &[
    "-1",
    "0",
    "1",
    "1e300",
    "-1e300",
    "1e-300",
    "NaN",
    "inf",
    "-inf",
    "18446744073709551616",
    "18446744073709551615",
    "4294967296",
    "9223372036854775807",
    "-0.0",
    "0.0",
    "3",
    "100000",
];

const INSERTS: &[char] = &[
    '(', ')', '[', ']', ',', ':', '"', '0', '-', '.', 'e', ' ', '\n',
];

fn char_positions(s: &str) -> Vec<usize> {
    s.char_indices().map(|(i, _)| i).collect()
}

/// Byte ranges of the numbers in `s`.
fn numbers(s: &str) -> Vec<(usize, usize)> {
    let b = s.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let starts =
            b[i].is_ascii_digit() || (b[i] == b'-' && i + 1 < b.len() && b[i + 1].is_ascii_digit());
        let prev_ident = i > 0 && (b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_');
        if starts && !prev_ident {
            let mut j = i + 1;
            while j < b.len()
                && (b[j].is_ascii_digit() || matches!(b[j], b'.' | b'e' | b'E' | b'+' | b'-'))
            {
                j += 1;
            }
            out.push((i, j));
            i = j;
        } else {
            i += 1;
        }
    }
    out
}

/// Byte ranges of field names (identifiers followed by `:`).
fn field_names(s: &str) -> Vec<(usize, usize)> {
    let b = s.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if b[i].is_ascii_alphabetic() || b[i] == b'_' {
            let mut j = i;
            while j < b.len() && (b[j].is_ascii_alphanumeric() || b[j] == b'_') {
                j += 1;
            }
            let rest = s[j..].trim_start();
            if rest.starts_with(':') {
                out.push((i, j));
            }
            i = j;
        } else {
            i += 1;
        }
    }
    out
}

fn mutate(text: &str, rng: &mut Rng) -> String {
    let mut s = text.to_string();
    let n = 1 + rng.below(3);
    for _ in 0..n {
        let pos = char_positions(&s);
        if pos.is_empty() {
            break;
        }
        let at = pos[rng.below(pos.len())];
        let ch_len = s[at..].chars().next().map_or(0, |c| c.len_utf8());
        match rng.below(9) {
            0 => {
                s.replace_range(at..at + ch_len, "");
            }
            1 => {
                let c = s[at..at + ch_len].to_string();
                s.insert_str(at, &c);
            }
            2 => {
                let next = at + ch_len;
                if let Some(c2) = s[next..].chars().next() {
                    let c1 = s[at..next].to_string();
                    let c2 = c2.to_string();
                    s.replace_range(at..next + c2.len(), &format!("{c2}{c1}"));
                }
            }
            3 => s.truncate(at),
            4 | 5 => {
                let nums = numbers(&s);
                if !nums.is_empty() {
                    let (a, b) = nums[rng.below(nums.len())];
                    s.replace_range(a..b, NUMBERS[rng.below(NUMBERS.len())]);
                }
            }
            6 => {
                let names = field_names(&s);
                if !names.is_empty() {
                    let (a, b) = names[rng.below(names.len())];
                    let new = match rng.below(3) {
                        0 => format!("{}x", &s[a..b]),
                        1 => {
                            let (c, d) = names[rng.below(names.len())];
                            s[c..d].to_string()
                        }
                        _ => String::new(),
                    };
                    s.replace_range(a..b, &new);
                }
            }
            7 => {
                let brackets: Vec<usize> = s
                    .char_indices()
                    .filter(|(_, c)| "()[]".contains(*c))
                    .map(|(i, _)| i)
                    .collect();
                if !brackets.is_empty() {
                    let i = brackets[rng.below(brackets.len())];
                    s.replace_range(i..i + 1, "");
                }
            }
            _ => {
                let c = INSERTS[rng.below(INSERTS.len())];
                s.insert(at, c);
            }
        }
    }
    s
}

fn bundled_scenes() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut v: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .collect();
    v.sort();
    v
}

#[test]
fn mutated_scenes_never_panic_the_loader() {
    let scenes = bundled_scenes();
    assert!(scenes.len() >= 4);
    let work = std::env::temp_dir().join(format!("tumble-fuzz-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&work);
    std::fs::create_dir_all(&work).unwrap();
    // Mesh paths are relative to the scene file: the mutated scenes see the bundled meshes.
    #[cfg(unix)]
    std::os::unix::fs::symlink(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/meshes"),
        work.join("meshes"),
    )
    .unwrap();
    let t0 = std::time::Instant::now();
    // TUMBLE_FUZZ_SEED and TUMBLE_FUZZ_CASES explore further; the default is fixed.
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<u64>().ok());
    let seed = env("TUMBLE_FUZZ_SEED").unwrap_or(0x9E37_79B9_7F4A_7C15) | 1;
    let cases = env("TUMBLE_FUZZ_CASES").map_or(CASES, |c| c as usize);
    let mut rng = Rng(seed);
    let mut panics = Vec::new();
    let mut bad_errors = Vec::new();
    let (mut loaded, mut rejected) = (0, 0);
    let per_scene = cases.div_ceil(scenes.len());
    for scene in &scenes {
        let text = std::fs::read_to_string(scene).unwrap();
        let stem = scene.file_stem().unwrap().to_string_lossy().into_owned();
        for k in 0..per_scene {
            let mutated = mutate(&text, &mut rng);
            let path = work.join(format!("{stem}-{k}.ron"));
            std::fs::write(&path, &mutated).unwrap();
            let result = std::panic::catch_unwind(|| Scene::load(&path));
            match result {
                Err(_) => {
                    let keep = work.join(format!("panic-{stem}-{k}.ron"));
                    std::fs::write(&keep, &mutated).unwrap();
                    panics.push(keep);
                }
                Ok(Ok(s)) => {
                    loaded += 1;
                    // What `tumble check` and the run compute from a loaded scene fits.
                    let g = s.grid();
                    let nodes = g.n.iter().try_fold(1usize, |a, &n| a.checked_mul(n));
                    assert!(
                        nodes.is_some_and(|n| n as u64 <= tumble::scene::MAX_NODES),
                        "{stem}-{k}: grid {:?}",
                        g.n
                    );
                    assert!(g.h.is_finite() && g.h > 0.0, "{stem}-{k}: h = {}", g.h);
                }
                Ok(Err(e)) => {
                    rejected += 1;
                    let msg = e.to_string();
                    let file = path.display().to_string();
                    // A located error points into the text.
                    let lines = mutated.lines().count().max(1);
                    let off_text = e.line.is_some_and(|l| l == 0 || l > lines);
                    if e.message.trim().is_empty()
                        || !msg.contains(&file)
                        || e.file != file
                        || off_text
                    {
                        bad_errors.push(format!("{stem}-{k}: {msg}"));
                    }
                }
            }
            let _ = std::fs::remove_file(&path);
        }
    }
    eprintln!(
        "{} cases: {loaded} loaded, {rejected} rejected, {} panics, {:.1} s",
        per_scene * scenes.len(),
        panics.len(),
        t0.elapsed().as_secs_f64()
    );
    assert!(
        panics.is_empty(),
        "the loader panicked on {} inputs, kept as {:?}",
        panics.len(),
        &panics[..panics.len().min(10)]
    );
    assert!(
        bad_errors.is_empty(),
        "{:#?}",
        &bad_errors[..bad_errors.len().min(10)]
    );
    assert!(
        rejected > cases / 4 && loaded > 0,
        "{loaded} loaded, {rejected} rejected"
    );
    let _ = std::fs::remove_dir_all(&work);
}
