//! Bad input, broadly: a seeded mutation fuzzer of the scene loader.
//!
//! Inputs are arbitrary bytes, and the shipped scenes (`cases/*.ron`) plus a solid scene with
//! random edits: characters replaced, ranges deleted or duplicated, numbers replaced by huge,
//! tiny, negative, zero, NaN or infinite values, identifiers swapped. For every input,
//! `Scene::from_str_at` must not panic, and a rejection must be an error whose message names
//! the file with `line:column` or the field. Scenes that parse, on at most 4096 cells, go on to
//! `Simulation::new`, which must not panic either and must name the file, a field, a stage or
//! a law when it refuses.
//!
//! Deterministic (fixed seed). `EFSI_FUZZ_CASES=N` runs N mutated scenes instead of the
//! default 15000 (plus N/3 byte strings; ≈ 0.7 s); `EFSI_FUZZ_SEED` changes the seed.

use efsi_core::Scene;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

struct Rng(u64);

impl Rng {
    /// A generator for `seed`: the seed is mixed (SplitMix64) into a non-zero state, so that
    /// different seeds give different streams (`seed | 1` made seeds 2 and 3 the same).
    fn new(seed: u64) -> Rng {
        let mut z = seed.wrapping_add(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        Rng(if z == 0 { 0x2545_f491_4f6c_dd1d } else { z })
    }
    fn next(&mut self) -> u64 {
        // xorshift64*
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// A scene with a solid, so that the law loader, VOF and elastic stages are reached too.
const SOLID: &str = r#"Scene(
    name: "fuzz_solid",
    domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
    grid: (nx: 12, ny: 12),
    time: (end: 0.1, cfl: 0.4, dt_max: 0.01),
    fluid: (density: 1.0, viscosity: 0.01),
    gravity: (0.0, -9.81),
    solid: (shape: Union([Disk(center: (0.5, 0.6), radius: 0.2), Rectangle(min: (0.1, 0.1), max: (0.3, 0.2))]),
            density: 2.0, velocity: (0.5, 0.0),
            law: (name: "neo_hookean", parameters: {"G": 100.0})),
    boundaries: (x_min: NoSlip, x_max: FreeSlip, y_min: NoSlip, y_max: MovingWall(speed: 1.0, profile: Sin2Ramp(width: 0.1), motion: Sin(omega: 2.0))),
    numerics: (projection: (tolerance: 1e-8), viscous: (theta: 0.5)),
    output: (vtk_every: 0.05, probe_every: 0.01,
             probes: [Point(name: "u_c", field: "u", at: (0.5, 0.5)), KineticEnergy, SolidVolume, SolidCentroid],
             profiles: [Line(name: "v", from: (0.5, 0.0), to: (0.5, 1.0), points: 9, fields: ["v"], at: [0.05])]),
)
"#;

const NUMBERS: &[&str] = &[
    "1e308",
    "-1e308",
    "1e-308",
    "0.0",
    "-0.0",
    "-1.0",
    "NaN",
    "inf",
    "-inf",
    "0",
    "-1",
    "4294967296",
    "18446744073709551615",
    "99999999999999999999999",
    "1e400",
    "5e-324",
    "3",
];

const WORDS: &[&str] = &[
    "Scene",
    "Planar",
    "Axisymmetric",
    "NoSlip",
    "Periodic",
    "Outflow",
    "Axis",
    "FreeSlip",
    "MovingWall",
    "Disk",
    "HalfPlane",
    "Some",
    "None",
    "true",
    "false",
    "()",
    "[]",
    "{}",
    "\"\"",
    "nx",
    "ny",
    "end",
    "solid",
    "law",
    "grid",
    "fixed_dt",
    "dt_min",
];

/// Replace the number starting at a random digit with one of [`NUMBERS`].
fn replace_number(text: &str, rng: &mut Rng) -> String {
    let digits: Vec<usize> = text
        .char_indices()
        .filter(|(_, c)| c.is_ascii_digit())
        .map(|(k, _)| k)
        .collect();
    if digits.is_empty() {
        return text.to_string();
    }
    let mut a = digits[rng.below(digits.len())];
    let b = text.as_bytes();
    let num = |c: u8| c.is_ascii_digit() || matches!(c, b'.' | b'e' | b'E' | b'-' | b'+');
    while a > 0 && num(b[a - 1]) {
        a -= 1;
    }
    let mut e = a;
    while e < b.len() && num(b[e]) {
        e += 1;
    }
    format!(
        "{}{}{}",
        &text[..a],
        NUMBERS[rng.below(NUMBERS.len())],
        &text[e..]
    )
}

fn char_boundary(text: &str, mut k: usize) -> usize {
    while !text.is_char_boundary(k) {
        k -= 1;
    }
    k
}

/// One to three random edits of `text`.
fn mutate(text: &str, rng: &mut Rng) -> String {
    let mut s = text.to_string();
    for _ in 0..1 + rng.below(3) {
        let n = s.len();
        let a = char_boundary(&s, rng.below(n + 1));
        let b = char_boundary(&s, (a + rng.below(40)).min(n));
        s = match rng.below(6) {
            0 | 1 => replace_number(&s, rng),
            2 => format!("{}{}", &s[..a], &s[b..]),
            3 => format!("{}{}{}", &s[..b], &s[a..b], &s[b..]),
            4 => {
                let c = b" (),:[]{}\"-.0123456789eaxyz_\n"[rng.below(29)] as char;
                format!("{}{c}{}", &s[..a], &s[char_boundary(&s, (a + 1).min(n))..])
            }
            _ => format!("{}{}{}", &s[..a], WORDS[rng.below(WORDS.len())], &s[b..]),
        };
    }
    s
}

/// Whether a loader message names where the problem is.
fn locates(msg: &str, path: &str) -> bool {
    let rest = msg.strip_prefix(path).unwrap_or("");
    // `path:line:col: …` or `path: field: …`
    let line_col = rest
        .strip_prefix(':')
        .and_then(|r| r.split(':').next())
        .is_some_and(|n| n.parse::<usize>().is_ok());
    let field = rest
        .strip_prefix(": ")
        .and_then(|r| r.split(": ").next())
        .is_some_and(|f| !f.is_empty() && !f.contains(' '));
    line_col || field
}

#[derive(Default, Debug)]
struct Tally {
    parsed: usize,
    refused: usize,
    built: usize,
    build_refused: usize,
}

fn check(text: &str, path: &Path, tally: &mut Tally) {
    let shown = path.display().to_string();
    let parsed = catch_unwind(|| Scene::from_str_at(text, path));
    let scene = match parsed {
        Err(_) => panic!("Scene::from_str_at panicked on:\n{text}"),
        Ok(Err(e)) => {
            tally.refused += 1;
            let m = e.to_string();
            assert!(
                locates(&m, &shown),
                "the message does not locate the problem: {m}\n--- input:\n{text}"
            );
            return;
        }
        Ok(Ok(s)) => s,
    };
    tally.parsed += 1;
    if scene.grid.nx.saturating_mul(scene.grid.ny) > 4096 {
        return;
    }
    let built = catch_unwind(AssertUnwindSafe(|| {
        efsi_run::simulation(scene, path, &efsi_stages::builtin())
    }));
    match built {
        Err(_) => panic!("Simulation::new panicked on:\n{text}"),
        Ok(Ok(_)) => tally.built += 1,
        Ok(Err(e)) => {
            tally.build_refused += 1;
            let m = e.to_string();
            assert!(
                !m.is_empty()
                    && (locates(&m, &shown) || m.contains("stage `") || m.contains("law `")),
                "Simulation::new's refusal does not say where: {m}\n--- input:\n{text}"
            );
        }
    }
}

#[test]
fn the_scene_loader_survives_arbitrary_and_mutated_input() {
    let start = std::time::Instant::now();
    let cases: usize = std::env::var("EFSI_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(15000);
    let seed: u64 = std::env::var("EFSI_FUZZ_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0x00EF_5100_F022);
    let mut rng = Rng::new(seed);
    let cases_dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../cases");
    let mut seeds: Vec<String> = std::fs::read_dir(&cases_dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .map(|p| std::fs::read_to_string(p).unwrap())
        .collect();
    assert!(seeds.len() >= 3, "cases/*.ron not found");
    seeds.push(SOLID.to_string());
    // The seeds themselves are valid.
    for s in &seeds {
        Scene::from_str_at(s, Path::new("seed.ron")).unwrap_or_else(|e| panic!("{e}"));
    }
    // Law paths in mutated scenes resolve relative to here: nothing to find.
    let path = std::env::temp_dir().join("efsi-fuzz/fuzz.ron");
    let mut tally = Tally::default();
    for _ in 0..cases / 3 {
        let n = rng.below(300);
        let bytes: Vec<u8> = (0..n).map(|_| rng.next() as u8).collect();
        check(&String::from_utf8_lossy(&bytes), &path, &mut tally);
    }
    for k in 0..cases {
        let text = mutate(&seeds[k % seeds.len()], &mut rng);
        check(&text, &path, &mut tally);
    }
    let secs = start.elapsed().as_secs_f64();
    eprintln!("{} inputs in {secs:.2} s: {tally:?}", cases + cases / 3);
    // The mutations must reach past the parser, and Simulation::new, in both directions.
    assert!(tally.parsed > cases / 10, "{tally:?}");
    assert!(tally.built > 0 && tally.build_refused > 0, "{tally:?}");
    assert!(tally.refused > cases / 3, "{tally:?}");
}

#[test]
fn different_seeds_give_different_streams() {
    let streams: Vec<Vec<u64>> = (0..64u64)
        .map(|seed| {
            let mut r = Rng::new(seed);
            (0..4).map(|_| r.next()).collect()
        })
        .collect();
    for a in 0..streams.len() {
        for b in a + 1..streams.len() {
            assert_ne!(streams[a], streams[b], "seeds {a} and {b}");
        }
    }
}
