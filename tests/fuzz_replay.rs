//! The loader fuzz targets on stable Rust, in every CI run: each body of
//! `prism::scene::fuzz` (the same code cargo-fuzz drives in scripts/fuzz) over the seeds
//! scripts/fuzz starts from, the inputs that once crashed (fuzz/regressions/TARGET/), and a
//! fixed number of random mutations of them from a fixed PRNG seed.
//!
//! What this is not: libFuzzer. No coverage guidance, so it explores far less than the
//! millions of executions in docs/RELIABILITY.md; the test build has no overflow checks
//! (`cargo test --release`), so an overflow that wraps quietly is not a failure here, as it
//! is under `scripts/fuzz` (`-a`); and memory is not limited per input. It catches a panic
//! or a broken promise on inputs near the bundled scenes and meshes, deterministically:
//! the same inputs every run. `PRISM_FUZZ_RUNS=N` changes the number of mutations per
//! target and `PRISM_FUZZ_SEED=S` the PRNG seed, to look further by hand. A failing input
//! is written to target/fuzz-replay/TARGET-failure for `cargo fuzz run TARGET FILE`.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Mutations per target by default. At the rates measured on the 2-core CI machine (see
/// docs/RELIABILITY.md) the three targets together take well under a minute.
const DEFAULT_RUNS: u64 = 20_000;

/// One input may take this long before it counts as a hang: scripts/fuzz's libFuzzer
/// `-timeout=10`. The fuzz bodies bound the work of a valid input to milliseconds
/// (`prism::scene::fuzz`), so even a loaded machine stays far below it.
const HANG: Duration = Duration::from_secs(10);

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn files(dir: &Path, ext: &str) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> =
        std::fs::read_dir(dir).map(|d| d.map(|e| e.unwrap().path()).collect()).unwrap_or_default();
    v.retain(|p| ext.is_empty() || p.extension().is_some_and(|e| e == ext));
    v.sort();
    v
}

fn read(p: &Path) -> Vec<u8> {
    std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The seeds scripts/fuzz makes, made the same way, plus fuzz/regressions/TARGET/.
fn seeds(target: &str) -> Vec<Vec<u8>> {
    let scenes = files(&root().join("assets/scenes"), "toml");
    let mut seeds = Vec::new();
    match target {
        "scene" => {
            for f in &scenes {
                let text = read(f);
                seeds.push(text.clone());
                let mut with_set = text;
                for o in [
                    "render.refraction=wyman",
                    "objects.0.material=\"glass\"",
                    "camera.position=[0, 1, 5]",
                    "render.hu_qin.search_steps=4",
                ] {
                    with_set.push(0);
                    with_set.extend_from_slice(o.as_bytes());
                }
                seeds.push(with_set);
            }
        }
        "volume" => {
            for f in scenes.iter().filter(|f| f.file_name().unwrap().to_string_lossy().starts_with("eikonal_")) {
                // Small voxel grids, so that the body evaluates them.
                let text = String::from_utf8(read(f)).unwrap();
                let small: Vec<String> = text
                    .lines()
                    .map(
                        |l| if l.starts_with("resolution = [") { "resolution = [12, 12, 12]".into() } else { l.into() },
                    )
                    .collect();
                seeds.push((small.join("\n") + "\n").into_bytes());
            }
        }
        "obj" => {
            for f in files(&root().join("assets/meshes"), "obj") {
                // The first 300 vertices and the faces that use only them.
                let text = String::from_utf8(read(&f)).unwrap();
                let mut out = String::new();
                let mut vertices = 0;
                for l in text.lines() {
                    let mut w = l.split_whitespace();
                    match w.next() {
                        Some("v") => {
                            vertices += 1;
                            if vertices > 300 {
                                continue;
                            }
                        }
                        Some("f") if w.any(|c| c.split('/').next().unwrap().parse::<i64>().unwrap_or(0) > 300) => {
                            continue
                        }
                        _ => {}
                    }
                    out.push_str(l);
                    out.push('\n');
                }
                seeds.push(out.into_bytes());
            }
            seeds.push(
                b"v 0 0 0\nv 1 0 0\nv 1 0 -1\nv 0 0 -1\nvn 0 1 0\nvt 0 0\nf -4/1/1 -3/1/1 -2/1/1 -1/1/1\n".to_vec(),
            );
            seeds.push(
                b"o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\ng b\nf 1 2 3\nusemtl m\nl 1 2\np 3\nf 1//1 2//1 3//1\n".to_vec(),
            );
        }
        _ => unreachable!(),
    }
    for f in files(&root().join("fuzz/regressions").join(target), "") {
        seeds.push(read(&f));
    }
    assert!(seeds.len() >= 3, "{target}: only {} seeds", seeds.len());
    seeds
}

/// Words that mutations insert: the scene files' keys and values, the syntax around them,
/// and numbers at the edges of the ranges the loaders check.
fn dictionary() -> Vec<Vec<u8>> {
    let mut words: Vec<String> = Vec::new();
    for f in files(&root().join("assets/scenes"), "toml") {
        let text = String::from_utf8(read(&f)).unwrap();
        for w in text.split(|c: char| !(c.is_ascii_lowercase() || c == '_')) {
            if w.len() >= 3 && !words.iter().any(|x| x == w) {
                words.push(w.to_string());
            }
        }
    }
    let edges = [
        "0",
        "-1",
        "1e38",
        "-1e38",
        "1e-30",
        "1e30",
        "nan",
        "inf",
        "-inf",
        "4294967295",
        "4294967296",
        "18446744073709551616",
        "65536",
        "8192",
        "1e4",
        "1e-3",
        "[",
        "]",
        "[[",
        "]]",
        "{",
        "}",
        "=",
        ",",
        ".",
        "\"",
        "\n",
        "\0",
        "/",
        "-",
        "#",
        " ",
        "\\u0000",
        "f ",
        "v ",
        "vn ",
        "vt ",
        "//",
        "[volume]",
        "[[volume.region]]",
        "[[objects]]",
        "render.",
        "objects.0.",
        "=[0,0,0]",
    ];
    words.extend(edges.iter().map(|s| s.to_string()));
    words.into_iter().map(String::into_bytes).collect()
}

/// splitmix64: a fixed sequence from a fixed seed, so that every run tries the same inputs.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// One to four of libFuzzer's kinds of byte mutation: bit flip, random byte, insertion and
/// erasure of bytes, a copied range, a dictionary word, a splice with another seed, a digit.
fn mutate(rng: &mut Rng, seeds: &[Vec<u8>], dict: &[Vec<u8>], max_len: usize) -> Vec<u8> {
    let mut d = seeds[rng.below(seeds.len())].clone();
    for _ in 0..1 + rng.below(4) {
        let at = rng.below(d.len() + 1);
        match rng.below(8) {
            0 if !d.is_empty() => {
                let i = at.min(d.len() - 1);
                d[i] ^= 1 << rng.below(8);
            }
            1 if !d.is_empty() => {
                let i = at.min(d.len() - 1);
                d[i] = rng.next() as u8;
            }
            2 => d.insert(at, rng.next() as u8),
            3 => {
                let end = (at + 1 + rng.below(16)).min(d.len());
                d.drain(at.min(end)..end);
            }
            4 if !d.is_empty() => {
                let from = rng.below(d.len());
                let len = 1 + rng.below(64.min(d.len() - from));
                let chunk = d[from..from + len].to_vec();
                d.splice(at..at, chunk);
            }
            5 | 6 => {
                let w = &dict[rng.below(dict.len())];
                d.splice(at..at, w.iter().copied());
            }
            7 => {
                let other = &seeds[rng.below(seeds.len())];
                let cut = rng.below(other.len() + 1);
                d.truncate(at);
                d.extend_from_slice(&other[cut..]);
            }
            _ => {
                if let Some(i) = (at..d.len()).find(|&i| d[i].is_ascii_digit()) {
                    d[i] = b'0' + rng.below(10) as u8;
                }
            }
        }
    }
    d.truncate(max_len);
    d
}

fn env_u64(name: &str, default: u64) -> u64 {
    std::env::var(name).ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

/// Every seed, then `PRISM_FUZZ_RUNS` mutations; fails on the first panic or hang with the
/// input written out.
fn replay(target: &str, body: fn(&[u8]), max_len: usize) {
    let seeds = seeds(target);
    let dict = dictionary();
    let runs = env_u64("PRISM_FUZZ_RUNS", DEFAULT_RUNS);
    let mut rng = Rng(env_u64("PRISM_FUZZ_SEED", 0x5052_4953_4d00) ^ target.len() as u64);
    let start = Instant::now();
    let (mut slowest, mut executions) = (Duration::ZERO, 0u64);
    let inputs = seeds.iter().cloned().map(Some).chain((0..runs).map(|_| None));
    for (n, input) in inputs.enumerate() {
        let input = input.unwrap_or_else(|| mutate(&mut rng, &seeds, &dict, max_len));
        let t = Instant::now();
        let result = catch_unwind(AssertUnwindSafe(|| body(&input)));
        let took = t.elapsed();
        slowest = slowest.max(took);
        executions += 1;
        let failure = match result {
            Err(e) => Some(
                e.downcast_ref::<String>()
                    .cloned()
                    .or(e.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default(),
            ),
            Ok(()) if took > HANG => Some(format!("took {took:?} (a hang: more than {HANG:?})")),
            Ok(()) => None,
        };
        if let Some(why) = failure {
            let dir = root().join("target/fuzz-replay");
            std::fs::create_dir_all(&dir).unwrap();
            let path = dir.join(format!("{target}-failure"));
            std::fs::write(&path, &input).unwrap();
            panic!("{target}: input {n} failed: {why}\ninput written to {}", path.display());
        }
    }
    eprintln!(
        "{target}: {executions} executions ({} seeds) in {:.1} s, slowest input {slowest:?}",
        seeds.len(),
        start.elapsed().as_secs_f64()
    );
}

// The inputs' size limits are scripts/fuzz's `-max_len`.

#[test]
fn scene_and_overrides() {
    replay("scene", prism::scene::fuzz::scene, 8192);
}

#[test]
fn obj_loader() {
    replay("obj", prism::scene::fuzz::obj, 65536);
}

#[test]
fn volume_sources() {
    replay("volume", prism::scene::fuzz::volume, 8192);
}
