//! Fuzz test of the scene loader, CPU only: random mutations of the shipped
//! scenes' TOML, OBJ and MTL files must each load to `Ok` or to a clean `SceneError` (a
//! non-empty message that names a file of the scene and has no "panicked" in it), never a
//! panic; a scene that loads must keep the loader's promises (`broken_invariant`).
//!
//! The scenes of `SCENES` (all shipped ones but the slow car-headlights and moving-sun) are
//! copied into a scratch folder; each case picks a scene (by weight) and one of its TOML, OBJ or
//! MTL files (a luminaire's TOML included), applies one random edit (a quarter of the cases two
//! or three) to its text, writes it, calls `irad::scene::load` under `catch_unwind` and puts
//! the original back. EXR files are copied but never mutated. Edits: delete a byte range,
//! duplicate a line, swap two lines, replace a number with an extreme value (1e30, -1, 0, nan,
//! inf, 1e-40, 4294967296, a huge integer, "", ...), insert random bytes (NUL and non-UTF-8
//! among them), truncate, rename a key (TOML key or table, OBJ/MTL keyword), break an OBJ face
//! corner (index 0, negative, out of range, malformed) and insert a suspicious line. Every
//! failing case is collected and the test fails at the end listing them all (case, scene, file,
//! edits, panic message and location or error, an excerpt of the mutated text).
//!
//! Seed `SEED` (splitmix64), `CASES` = 3000 cases: 2.8 s measured in debug on 2 cores (about
//! 0.2 to 3 ms a case, 30 ms for headlight-wall); `--nocapture` prints the time.
//! `IRAD_SCENE_FUZZ_SEED` (decimal or 0x hex) and `IRAD_SCENE_FUZZ_CASES` override both for a
//! longer hunt by hand.

use std::cell::RefCell;
use std::panic::{self, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::time::Instant;

const SEED: u64 = 0x1AD5_CE4E_F022_0005;
const CASES: usize = 3000;

/// The shipped scenes fuzzed (folders under scenes/) and their weights: the small ones load in
/// about a millisecond; headlight-wall, with a light-field luminaire (its atlas is 476 KiB and
/// the scene takes about 30 ms), gets a few cases only; cornell-circling's animation tracks are
/// fuzzed through its TOML (it reads cornell-box's OBJ, copied before it). car-headlights (the same luminaire
/// twice, about 70 ms) and moving-sun (a procedural sky of 64 maps) are left out as slow.
const SCENES: &[(&str, usize)] = &[
    ("cornell-box", 10),
    ("cornell-circling", 10),
    ("spot-light", 10),
    ("point-light-plane", 10),
    ("glossy-env", 10),
    ("failure/corner-light", 10),
    ("failure/glossy-cornell", 10),
    ("failure/glossy-walls", 10),
    ("failure/u-office", 10),
    ("failure/sun-behind", 10),
    ("failure/conference-room", 10),
    ("failure/halogen-office", 10),
    ("failure/headlight-wall", 3),
];

/// splitmix64: a fixed seed gives the same mutations on every run and machine.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in 0..n (n > 0).
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    /// Uniform in lo..=hi.
    fn range(&mut self, lo: usize, hi: usize) -> usize {
        lo + self.below(hi - lo + 1)
    }

    fn chance(&mut self, num: usize, den: usize) -> bool {
        self.below(den) < num
    }

    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Toml,
    Obj,
    Mtl,
}

/// A scene copied to the scratch folder, with the original bytes of its mutable files.
struct FuzzScene {
    name: &'static str,
    dir: PathBuf,
    /// (file name, kind, original bytes), sorted by name.
    files: Vec<(String, Kind, Vec<u8>)>,
}

/// The scratch folder, unique to this process, removed when dropped (also on a failure).
struct Scratch(PathBuf);

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The files under `dir`, recursively, as paths relative to it, sorted.
fn files_under(dir: &Path) -> Vec<PathBuf> {
    let mut out = vec![];
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let name = PathBuf::from(path.file_name().unwrap());
        if path.is_dir() {
            out.extend(files_under(&path).into_iter().map(|p| name.join(p)));
        } else if path.is_file() {
            out.push(name);
        }
    }
    out.sort();
    out
}

/// Copies scenes/`name` into `scratch`: its TOML, OBJ and MTL files, and the EXR files a TOML
/// of it names (not the cached references beside the Cornell box).
fn copy_scene(name: &'static str, scratch: &Path) -> FuzzScene {
    let src = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name);
    let dir = scratch.join(name);
    let rels = files_under(&src);
    let ext = |rel: &Path| rel.extension().map(|e| e.to_string_lossy().into_owned());
    let tomls: Vec<String> = rels
        .iter()
        .filter(|rel| ext(rel).as_deref() == Some("toml"))
        .map(|rel| std::fs::read_to_string(src.join(rel)).unwrap())
        .collect();
    let mut files = vec![];
    for rel in rels {
        let file_name = rel.file_name().unwrap().to_string_lossy().into_owned();
        let kind = match ext(&rel).as_deref() {
            Some("toml") => Some(Kind::Toml),
            Some("obj") => Some(Kind::Obj),
            Some("mtl") => Some(Kind::Mtl),
            Some("exr") if tomls.iter().any(|t| t.contains(&file_name)) => None,
            _ => continue,
        };
        let bytes = std::fs::read(src.join(&rel)).unwrap();
        let to = dir.join(&rel);
        std::fs::create_dir_all(to.parent().unwrap()).unwrap();
        std::fs::write(&to, &bytes).unwrap();
        if let Some(kind) = kind {
            files.push((rel.to_string_lossy().into_owned(), kind, bytes));
        }
    }
    FuzzScene { name, dir, files }
}

/// Byte ranges of the lines of `text`, each with its '\n' when it has one.
fn lines(text: &[u8]) -> Vec<(usize, usize)> {
    let mut out = vec![];
    let mut start = 0;
    for (i, &b) in text.iter().enumerate() {
        if b == b'\n' {
            out.push((start, i + 1));
            start = i + 1;
        }
    }
    if start < text.len() {
        out.push((start, text.len()));
    }
    out
}

/// Byte ranges of the number-like tokens of `text`: runs of [0-9+-.eE] holding a digit.
fn numbers(text: &[u8]) -> Vec<(usize, usize)> {
    let numeric = |b: u8| b.is_ascii_digit() || matches!(b, b'+' | b'-' | b'.' | b'e' | b'E');
    let mut out = vec![];
    let mut i = 0;
    while i < text.len() {
        if numeric(text[i]) {
            let start = i;
            while i < text.len() && numeric(text[i]) {
                i += 1;
            }
            if text[start..i].iter().any(u8::is_ascii_digit) {
                out.push((start, i));
            }
        } else {
            i += 1;
        }
    }
    out
}

/// Byte ranges of the first word of each line that has one (an OBJ/MTL keyword, a TOML key or
/// table name without its brackets).
fn keys(text: &[u8]) -> Vec<(usize, usize)> {
    let word = |b: u8| !b.is_ascii_whitespace() && !matches!(b, b'[' | b']' | b'=');
    lines(text)
        .into_iter()
        .filter_map(|(s, e)| {
            let mut i = s;
            while i < e && matches!(text[i], b' ' | b'\t' | b'[') {
                i += 1;
            }
            let start = i;
            while i < e && word(text[i]) {
                i += 1;
            }
            (i > start).then_some((start, i))
        })
        .collect()
}

const EXTREMES: &[&str] = &[
    "1e30",
    "-1e30",
    "-1",
    "0",
    "-0",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "+inf",
    "1e-40",
    "1e39",
    "3.4028236e38",
    "4294967296",
    "-4294967296",
    "2147483648",
    "9223372036854775807",
    "-9223372036854775808",
    "9223372036854775808",
    "18446744073709551616",
    "340282366920938463463374607431768211456",
    "100000001",
    "65537",
    "180",
    "1e8",
    "0.0.0",
    "1e",
    "--1",
    "0x10",
    "\"\"",
    "",
];

const TOML_KEYS: &[&str] = &[
    "camera",
    "mesh",
    "light",
    "environment",
    "luminaire",
    "failure",
    "position",
    "look_at",
    "up",
    "fov_y",
    "resolution",
    "obj",
    "kind",
    "intensity",
    "direction",
    "cone_angle",
    "falloff_angle",
    "exr",
    "scale",
    "path",
    "methods",
    "why",
    "source",
    "colour",
    "camera.position",
    "\"fov_y\"",
    "",
];

const OBJ_MTL_KEYS: &[&str] = &[
    "v", "vn", "vt", "vp", "f", "l", "p", "o", "g", "s", "usemtl", "mtllib", "newmtl", "Kd", "Ks",
    "Ke", "Ns", "Ka", "d", "illum", "map_Kd", "#", "F", "V", "",
];

const FACE_CORNERS: &[&str] = &[
    "0",
    "-1",
    "-2",
    "-999999",
    "999999",
    "4294967296",
    "-4294967296",
    "9223372036854775807",
    "-9223372036854775808",
    "99999999999999999999",
    "1//0",
    "1/0",
    "1/1",
    "1//-1",
    "1//99",
    "-1//-1",
    "1/1/1",
    "1/1/1/1",
    "/1",
    "1/",
    "//",
    "1//",
    "1.5",
    "+1",
    "-0",
    "x",
    "",
];

const OBJ_LINES: &[&str] = &[
    "v 1e30 0 0",
    "v 0 0 0 0",
    "v 1 2",
    "v 1 2 3 4 5",
    "v 1 2 3 1e-45",
    "vn 0 0 0",
    "vn nan nan nan",
    "vn 1 0",
    "vt",
    "vt 0.5 x",
    "f 1 1 1",
    "f -1 -2 -3",
    "f 1",
    "f 1 2",
    "f",
    "f 1/1/1 2/2/2 3/3/3",
    "f 1//1 2//2 3//3",
    "l 1 2",
    "usemtl nonexistent",
    "usemtl",
    "mtllib missing.mtl",
    "mtllib",
    "mtllib ../../../../../../dev/null",
    "o",
    "g \u{0}",
    "v 100000000 0 0\nv 0 100000000 0\nv 0 0 1e-30\nf -1 -2 -3",
    "v 0 0 0\nv 1e-30 0 0\nv 0 1e-30 0\nf -1 -2 -3",
];

const MTL_LINES: &[&str] = &[
    "newmtl",
    "newmtl x",
    "Kd 1",
    "Kd 1 1",
    "Kd 1 1 1 1",
    "Kd",
    "Ke 1e38 1e38 1e38",
    "Ke 3.4e38",
    "Ks 1 1 1",
    "Ns -1",
    "Ns",
    "Ns 1 2",
    "Kd spectral a.spd",
    "Ke xyz 1 1 1",
    "Ke nan",
    "Ke -0",
];

const TOML_LINES: &[&str] = &[
    "[[light]]\nkind = \"point\"\nposition = [0, 1, 0]\nintensity = [1e30, 1, 1]",
    "[[light]]\nkind = \"spot\"\nposition = [0, 1, 0]\nintensity = [1, 1, 1]\ndirection = [0, 0, 0]\ncone_angle = 10\nfalloff_angle = 20",
    "[[light]]\nkind = \"point\"",
    "[environment]\nexr = \"*.exr\"",
    "[environment]\nexr = \"s?y.exr\"",
    "[environment]\nexr = \"sky[.exr\"",
    "[environment]\nexr = \"*/sky.exr\"",
    "[environment]\nexr = \"sky.exr\"\nscale = 1e38",
    "[environment]",
    "[[mesh]]\nobj = \"\"",
    "[[mesh]]\nobj = \"/\"",
    "[[mesh]]\nobj = \"missing.obj\"",
    "[[mesh]]\nobj = \"scene.toml\"",
    "[failure]\nmethods = []\nwhy = \"\"\nsource = \" \"",
    "[camera]",
    "resolution = [0, 0]",
    "[[luminaire]]\npath = \"missing/luminaire.toml\"\nposition = [0, 1, 0]\nlook_at = [0, 0, 0]",
    "= 1",
    "[",
    "\"\"\"",
];

/// Applies one random edit to `text` (a `kind` file); returns what it did and where.
fn mutate(rng: &mut Rng, text: &mut Vec<u8>, kind: Kind) -> (String, usize) {
    let len = text.len();
    match rng.below(10) {
        0 if len > 0 => {
            let start = rng.below(len);
            let n = rng.range(1, (len - start).min(64));
            text.drain(start..start + n);
            (format!("deleted bytes {start}..{}", start + n), start)
        }
        1 => {
            let ls = lines(text);
            if ls.is_empty() {
                return mutate(rng, text, kind);
            }
            let (s, e) = *rng.pick(&ls);
            let mut line = text[s..e].to_vec();
            if line.last() != Some(&b'\n') {
                line.insert(0, b'\n');
            }
            text.splice(e..e, line);
            (format!("duplicated the line at byte {s}"), s)
        }
        2 => {
            let ls = lines(text);
            if ls.len() < 2 {
                return mutate(rng, text, kind);
            }
            let (i, j) = (rng.below(ls.len()), rng.below(ls.len()));
            let (i, j) = (i.min(j), i.max(j));
            if i == j {
                return mutate(rng, text, kind);
            }
            let line = |k: usize| {
                let (s, e) = ls[k];
                let mut l = text[s..e].to_vec();
                if l.last() != Some(&b'\n') {
                    l.push(b'\n');
                }
                l
            };
            let mut out = text[..ls[i].0].to_vec();
            out.extend(line(j));
            out.extend_from_slice(&text[ls[i].1..ls[j].0]);
            out.extend(line(i));
            out.extend_from_slice(&text[ls[j].1..]);
            *text = out;
            (format!("swapped lines {} and {}", i + 1, j + 1), ls[i].0)
        }
        3 | 4 => {
            let ns = numbers(text);
            if ns.is_empty() {
                return mutate(rng, text, kind);
            }
            let (s, e) = *rng.pick(&ns);
            let value = *rng.pick(EXTREMES);
            let old = String::from_utf8_lossy(&text[s..e]).into_owned();
            text.splice(s..e, value.bytes());
            (format!("number `{old}` at byte {s} -> `{value}`"), s)
        }
        5 => {
            const SPECIAL: &[u8] = &[
                0, 0xFF, 0xFE, 0xC3, 0x80, 0xE2, b'\n', b'\r', b' ', b'\t', b'"', b'\'', b'[',
                b']', b'=', b'/', b'#', b'-', b'.', b'\\', b'{', b'*', b'?', b',',
            ];
            let at = rng.below(len + 1);
            let n = rng.range(1, 8);
            let bytes: Vec<u8> = (0..n)
                .map(|_| {
                    if rng.chance(1, 2) {
                        rng.next() as u8
                    } else {
                        *rng.pick(SPECIAL)
                    }
                })
                .collect();
            let what = format!("inserted bytes {bytes:02x?} at byte {at}");
            text.splice(at..at, bytes);
            (what, at)
        }
        6 => {
            let at = rng.below(len + 1);
            text.truncate(at);
            (format!("truncated at byte {at}"), at)
        }
        7 => {
            let ks = keys(text);
            if ks.is_empty() {
                return mutate(rng, text, kind);
            }
            let (s, e) = *rng.pick(&ks);
            let new = match kind {
                Kind::Toml => *rng.pick(TOML_KEYS),
                Kind::Obj | Kind::Mtl => *rng.pick(OBJ_MTL_KEYS),
            };
            let old = String::from_utf8_lossy(&text[s..e]).into_owned();
            text.splice(s..e, new.bytes());
            (format!("key `{old}` at byte {s} -> `{new}`"), s)
        }
        8 if kind == Kind::Obj => {
            // A corner of an `f` line: replaced whole, or its normal index broken.
            let mut corners = vec![];
            for (s, e) in lines(text) {
                let line = &text[s..e];
                if line.starts_with(b"f ") {
                    let mut i = 2;
                    while i < line.len() {
                        if line[i].is_ascii_whitespace() {
                            i += 1;
                            continue;
                        }
                        let start = i;
                        while i < line.len() && !line[i].is_ascii_whitespace() {
                            i += 1;
                        }
                        corners.push((s + start, s + i));
                    }
                }
            }
            if corners.is_empty() {
                return mutate(rng, text, kind);
            }
            let (s, e) = *rng.pick(&corners);
            let old = String::from_utf8_lossy(&text[s..e]).into_owned();
            let new = if rng.chance(2, 3) {
                rng.pick(FACE_CORNERS).to_string()
            } else {
                let vertex = old.split('/').next().unwrap_or("");
                let bad = rng.pick(&FACE_CORNERS[..10]);
                format!("{vertex}//{bad}")
            };
            text.splice(s..e, new.bytes());
            (format!("face corner `{old}` at byte {s} -> `{new}`"), s)
        }
        _ => {
            let ls = lines(text);
            let at = if ls.is_empty() {
                0
            } else {
                ls[rng.below(ls.len())].0
            };
            let line = match kind {
                Kind::Toml => *rng.pick(TOML_LINES),
                Kind::Obj => *rng.pick(OBJ_LINES),
                Kind::Mtl => *rng.pick(MTL_LINES),
            };
            let what = format!("inserted line {line:?} at byte {at}");
            text.splice(at..at, format!("{line}\n").into_bytes());
            (what, at)
        }
    }
}

/// The 80 bytes of `text` around byte `at` (fewer at its ends), escaped.
fn excerpt(text: &[u8], at: usize) -> String {
    let at = at.min(text.len());
    let (s, e) = (at.saturating_sub(40), (at + 40).min(text.len()));
    String::from_utf8_lossy(&text[s..e])
        .escape_debug()
        .to_string()
}

/// What a loaded scene breaks of the loader's promises (src/scene/mod.rs), if anything: some
/// triangles, with finite positions within 1e8 (obj.rs `MAX_COORDINATE`), unit shading normals
/// and a material that exists; materials finite, non-negative and with Kd + Ks <= 1 (to the
/// 1e-5 tolerance of mtl.rs); a camera with a size and a field of view in (0, 180).
fn broken_invariant(scene: &irad::scene::Scene) -> Option<String> {
    if scene.triangles.is_empty() {
        return Some("no triangles".into());
    }
    for (i, t) in scene.triangles.iter().enumerate() {
        if !t
            .positions
            .iter()
            .all(|p| p.is_finite() && p.abs().max_element() <= 1e8)
        {
            return Some(format!("triangle {i} positions {:?}", t.positions));
        }
        if !t
            .normals
            .iter()
            .all(|n| n.is_finite() && (n.length() - 1.0).abs() < 1e-3)
        {
            return Some(format!("triangle {i} normals {:?}", t.normals));
        }
        if t.material as usize >= scene.materials.len() {
            return Some(format!("triangle {i} material {}", t.material));
        }
    }
    for m in &scene.materials {
        let channels = [m.kd, m.ks, m.ke];
        let ok = channels
            .iter()
            .all(|c| c.is_finite() && c.min_element() >= 0.0)
            && m.ns.is_finite()
            && m.ns >= 0.0
            && (m.kd + m.ks).max_element() <= 1.0 + 1e-5;
        if !ok {
            return Some(format!("material {m:?}"));
        }
    }
    let c = &scene.camera;
    if !(c.width >= 1 && c.height >= 1 && c.fov_y > 0.0 && c.fov_y < 180.0) {
        return Some(format!("camera {c:?}"));
    }
    None
}

thread_local! {
    /// The message and location of the last panic on this thread, set by the fuzz hook.
    static LAST_PANIC: RefCell<Option<String>> = const { RefCell::new(None) };
}

fn env_or<T: std::str::FromStr>(name: &str, default: T, parse: fn(&str) -> Option<T>) -> T {
    std::env::var(name)
        .ok()
        .map(|v| parse(v.trim()).unwrap_or_else(|| panic!("{name} = {v:?} is not valid")))
        .unwrap_or(default)
}

#[test]
fn mutated_scenes_load_or_fail_cleanly() {
    let seed = env_or("IRAD_SCENE_FUZZ_SEED", SEED, |v| {
        match v.strip_prefix("0x") {
            Some(hex) => u64::from_str_radix(&hex.replace('_', ""), 16).ok(),
            None => v.parse().ok(),
        }
    });
    let cases = env_or("IRAD_SCENE_FUZZ_CASES", CASES, |v| v.parse().ok());

    let scratch =
        Scratch(std::env::temp_dir().join(format!("irad-scene-fuzz-{}", std::process::id())));
    let _ = std::fs::remove_dir_all(&scratch.0);
    let scenes: Vec<FuzzScene> = SCENES
        .iter()
        .map(|(name, _)| copy_scene(name, &scratch.0))
        .collect();
    // Scene indices, each as many times as its weight.
    let draw: Vec<usize> = (0..SCENES.len())
        .flat_map(|i| std::iter::repeat_n(i, SCENES[i].1))
        .collect();
    // The fuzz starts from scenes that load.
    for s in &scenes {
        let t0 = Instant::now();
        let r = irad::scene::load(&s.dir.join("scene.toml"));
        println!("{}: {:.2} ms", s.name, t0.elapsed().as_secs_f64() * 1e3);
        if let Err(e) = r {
            panic!("{} does not load unmutated: {e}", s.name);
        }
        // cornell-circling holds its TOML alone: its mesh is cornell-box's copy, fuzzed there.
        let least = if s.name == "cornell-circling" { 1 } else { 2 };
        assert!(s.files.len() >= least, "{}: {:?}", s.name, s.files.len());
    }

    let previous_hook = panic::take_hook();
    panic::set_hook(Box::new(|info| {
        LAST_PANIC.with(|p| *p.borrow_mut() = Some(info.to_string()));
    }));

    let mut rng = Rng(seed);
    let mut failures: Vec<String> = vec![];
    let (mut ok, mut err) = (0usize, 0usize);
    let start = Instant::now();
    for case in 0..cases {
        let scene = &scenes[*rng.pick(&draw)];
        let (file, kind, original) = &scene.files[rng.below(scene.files.len())];
        let mut text = original.clone();
        let edits = if rng.chance(3, 4) { 1 } else { rng.range(2, 3) };
        let mut what = vec![];
        let mut at = 0;
        for _ in 0..edits {
            let (w, a) = mutate(&mut rng, &mut text, *kind);
            what.push(w);
            at = a;
        }
        let path = scene.dir.join(file);
        std::fs::write(&path, &text).unwrap();
        LAST_PANIC.with(|p| p.borrow_mut().take());
        let result = panic::catch_unwind(AssertUnwindSafe(|| {
            irad::scene::load(&scene.dir.join("scene.toml"))
        }));
        std::fs::write(&path, original).unwrap();
        let context = || {
            format!(
                "case {case}: {}/{file}: {}\n    excerpt: \"{}\"",
                scene.name,
                what.join("; "),
                excerpt(&text, at)
            )
        };
        match result {
            Ok(Ok(loaded)) => {
                ok += 1;
                if let Some(problem) = broken_invariant(&loaded) {
                    failures.push(format!("{}\n    loaded, but {problem}", context()));
                }
            }
            Ok(Err(e)) => {
                err += 1;
                let message = e.to_string();
                // Every message names its file (src/scene/error.rs), here one in the scene's
                // folder or the scene file that referenced it.
                let names_file = message.contains(&*scene.dir.to_string_lossy());
                if message.trim().is_empty() || message.contains("panicked") || !names_file {
                    failures.push(format!("{}\n    unclean error: {message:?}", context()));
                }
            }
            Err(payload) => {
                let message = LAST_PANIC
                    .with(|p| p.borrow_mut().take())
                    .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
                    .or_else(|| payload.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "(no message)".into());
                failures.push(format!("{}\n    PANIC: {message}", context()));
            }
        }
    }
    let elapsed = start.elapsed();
    let _ = panic::take_hook();
    panic::set_hook(previous_hook);

    println!(
        "scene fuzz: seed {seed:#x}, {cases} cases in {:.2} s: {ok} Ok, {err} Err, {} failures",
        elapsed.as_secs_f64(),
        failures.len()
    );
    const SHOWN: usize = 100;
    assert!(
        failures.is_empty(),
        "{} of {cases} mutated scenes (seed {seed:#x}) panicked, gave an unclean error or loaded \
         broken:\n{}{}",
        failures.len(),
        failures
            .iter()
            .take(SHOWN)
            .cloned()
            .collect::<Vec<_>>()
            .join("\n"),
        if failures.len() > SHOWN {
            format!("\n... and {} more", failures.len() - SHOWN)
        } else {
            String::new()
        }
    );
}
