//! Wrong data are refused and named, valid data never: wrong units, a mirrored modality, another
//! patient, the other jaw, IOS labels shifted along the arch, two neighbouring labels swapped.
//! Each kind on ten seeds through the library, one seed of each through the C ABI and the CLI
//! (the rows of docs/errors.md); no false alarm over 21 phantom jaws (every variant, both jaws)
//! and the two foreign jaws. Phantoms are generated once and shared by the tests.

mod ffi_common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::{Mutex, OnceLock};
use std::time::Instant;
use toothfuse::arch::{Jaw, arch_order};
use toothfuse::ffi::*;
use toothfuse::mesh::TriMesh;
use toothfuse::phantom::{Phantom, PhantomOptions, Variant};
use toothfuse::register::{RegisterOptions, Registration, register};
use toothfuse::{ErrorKind, Result};

type Teeth = BTreeMap<u8, TriMesh>;

/// A generated phantom and its IOS crowns, shared by every test of this file.
struct Jaw3 {
    crowns: Teeth,
    cbct: Teeth,
}

fn phantom(seed: u64, jaw: Jaw, variant: Variant) -> &'static Jaw3 {
    type Key = (u64, Jaw, &'static str);
    type Slot = &'static Mutex<Option<&'static Jaw3>>;
    static CACHE: OnceLock<Mutex<BTreeMap<Key, Slot>>> = OnceLock::new();
    let slot = *CACHE
        .get_or_init(Default::default)
        .lock()
        .unwrap()
        .entry((seed, jaw, variant.name()))
        .or_insert_with(|| Box::leak(Box::new(Mutex::new(None))));
    let mut g = slot.lock().unwrap();
    if let Some(j) = *g {
        return j;
    }
    let p = Phantom::generate(&PhantomOptions {
        seed,
        jaw,
        variant,
        ..PhantomOptions::default()
    })
    .expect("phantom");
    let j: &'static Jaw3 = Box::leak(Box::new(Jaw3 {
        crowns: p.ios_crowns(),
        cbct: p.cbct,
    }));
    *g = Some(j);
    j
}

const SEEDS: std::ops::RangeInclusive<u64> = 1..=10;

fn scaled(t: &Teeth, f: f64) -> Teeth {
    t.iter()
        .map(|(&k, m)| {
            let mut m = m.clone();
            m.positions.iter_mut().for_each(|p| *p *= f);
            (k, m)
        })
        .collect()
}

/// x → −x with the faces reversed (still outward): a reflection, as an LPS/RAS slip makes.
fn mirrored(t: &Teeth) -> Teeth {
    t.iter()
        .map(|(&k, m)| {
            let mut m = m.clone();
            m.positions.iter_mut().for_each(|p| p.x = -p.x);
            m.triangles.iter_mut().for_each(|t| t.swap(1, 2));
            (k, m)
        })
        .collect()
}

/// Each crown takes the number of its neighbour one step along the arch (the last is dropped).
fn shifted(t: &Teeth) -> Teeth {
    let order = arch_order(&t.keys().copied().collect::<Vec<_>>());
    order.windows(2).map(|w| (w[1], t[&w[0]].clone())).collect()
}

/// Two neighbouring crowns exchange their numbers; returns them too.
fn swapped(t: &Teeth, seed: u64) -> (Teeth, u8, u8) {
    let order = arch_order(&t.keys().copied().collect::<Vec<_>>());
    let i = 1 + (seed as usize % (order.len() - 3));
    let (a, b) = (order[i], order[i + 1]);
    let mut m = t.clone();
    m.insert(a, t[&b].clone());
    m.insert(b, t[&a].clone());
    (m, a, b)
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Metres,
    Centimetres,
    MirroredIos,
    MirroredCbct,
    OtherPatient,
    OtherJaw,
    Shifted,
    Swapped,
}

const KINDS: [Kind; 8] = [
    Kind::Metres,
    Kind::Centimetres,
    Kind::MirroredIos,
    Kind::MirroredCbct,
    Kind::OtherPatient,
    Kind::OtherJaw,
    Kind::Shifted,
    Kind::Swapped,
];

/// What a wrong-data case must give: the jaw refused with this kind and these words, or (the
/// swapped pair) these teeth skipped with these words.
enum Expect {
    Refused(ErrorKind, Vec<&'static str>),
    Skipped(Vec<u8>, Vec<&'static str>),
}

/// The spoiled inputs of `kind` on `seed` (an upper full arch; the other patient is the next
/// seed, the other jaw a lower jaw), and what must come of them. Units alternate the modality
/// by seed.
fn case(kind: Kind, seed: u64) -> (Teeth, Teeth, Expect) {
    let p = phantom(seed, Jaw::Upper, Variant::Full);
    let (i, c) = (p.crowns.clone(), p.cbct.clone());
    let ios_side = seed % 2 == 1;
    match kind {
        Kind::Metres | Kind::Centimetres => {
            let (f, unit) = if kind == Kind::Metres {
                (0.001, "metres")
            } else {
                (0.1, "centimetres")
            };
            let (i, c, m) = if ios_side {
                (scaled(&i, f), c, "IOS")
            } else {
                (i, scaled(&c, f), "CBCT")
            };
            (
                i,
                c,
                Expect::Refused(ErrorKind::UnitMismatch, vec![m, unit]),
            )
        }
        Kind::MirroredIos => (
            mirrored(&i),
            c,
            Expect::Refused(ErrorKind::Mirrored, vec!["the IOS is mirrored"]),
        ),
        Kind::MirroredCbct => (
            i,
            mirrored(&c),
            Expect::Refused(ErrorKind::Mirrored, vec!["the CBCT is mirrored"]),
        ),
        Kind::OtherPatient => (
            phantom(seed + 1, Jaw::Upper, Variant::Full).crowns.clone(),
            c,
            Expect::Refused(ErrorKind::RegistrationRejected, vec!["another patient"]),
        ),
        Kind::OtherJaw => (
            lower_jaw(seed).crowns.clone(),
            c,
            Expect::Refused(ErrorKind::RegistrationRejected, vec!["wrong jaw"]),
        ),
        Kind::Shifted => (
            shifted(&i),
            c,
            Expect::Refused(
                ErrorKind::RegistrationRejected,
                vec!["labels shifted by one tooth along the arch"],
            ),
        ),
        Kind::Swapped => {
            let (s, a, b) = swapped(&i, seed);
            (
                s,
                c,
                Expect::Skipped(vec![a, b], vec!["misnumbered", "swapped"]),
            )
        }
    }
}

/// The lower jaws of the false-alarm set, by index (they double as "the other jaw").
fn lower_jaw(k: u64) -> &'static Jaw3 {
    match k {
        1..=4 => phantom(1, Jaw::Lower, Variant::ALL[k as usize]),
        _ => phantom(k - 4, Jaw::Lower, Variant::Full),
    }
}

fn check(
    kind: Kind,
    seed: u64,
    r: Result<Registration>,
    e: &Expect,
) -> std::result::Result<(), String> {
    match (e, r) {
        (Expect::Refused(k, words), Err(err)) => {
            let m = err.to_string();
            if err.kind() != *k || !words.iter().all(|w| m.contains(w)) {
                return Err(format!(
                    "{kind:?} seed {seed}: wrong cause: {:?} {m}",
                    err.kind()
                ));
            }
            Ok(())
        }
        (Expect::Refused(..), Ok(r)) => Err(format!(
            "{kind:?} seed {seed}: not caught (registered {} teeth, gate {:?})",
            r.teeth.len(),
            r.gate
        )),
        (Expect::Skipped(teeth, words), Ok(r)) => {
            for t in teeth {
                let Some(s) = r.skipped.iter().find(|s| s.fdi == *t) else {
                    return Err(format!(
                        "{kind:?} seed {seed}: tooth {t} not skipped: {:?}",
                        r.skipped
                    ));
                };
                if !words.iter().all(|w| s.reason.contains(w)) {
                    return Err(format!("{kind:?} seed {seed}: tooth {t}: {}", s.reason));
                }
            }
            if r.teeth.len() + teeth.len() < 14 {
                return Err(format!(
                    "{kind:?} seed {seed}: too few teeth kept: {:?}",
                    r.skipped
                ));
            }
            Ok(())
        }
        (Expect::Skipped(..), Err(err)) => Err(format!("{kind:?} seed {seed}: refused: {err}")),
    }
}

#[test]
fn every_wrong_data_kind_is_caught_on_ten_seeds() {
    let opts = RegisterOptions::default();
    let mut failures = Vec::new();
    let mut slowest = (0.0f64, Kind::Metres, 0);
    for seed in SEEDS {
        for kind in KINDS {
            let (i, c, e) = case(kind, seed);
            let t0 = Instant::now();
            let r = register(&i, &c, &opts);
            let s = t0.elapsed().as_secs_f64();
            if s > slowest.0 {
                slowest = (s, kind, seed);
            }
            if let Err(f) = check(kind, seed, r, &e) {
                failures.push(f);
            }
        }
    }
    println!(
        "slowest wrong-data registration: {:.2} s ({:?}, seed {})",
        slowest.0, slowest.1, slowest.2
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// 21 phantom jaws: upper full arches of the wrong-data seeds, every variant of both jaws, lower
/// full arches.
fn valid_jaws() -> Vec<(String, &'static Jaw3)> {
    let mut v: Vec<(String, &'static Jaw3)> = SEEDS
        .chain([11])
        .map(|s| {
            (
                format!("upper full {s}"),
                phantom(s, Jaw::Upper, Variant::Full),
            )
        })
        .collect();
    for var in &Variant::ALL[1..] {
        v.push((
            format!("upper {} 1", var.name()),
            phantom(1, Jaw::Upper, *var),
        ));
    }
    for k in 1..=6 {
        v.push((format!("lower #{k}"), lower_jaw(k)));
    }
    v
}

fn no_false_alarm(name: &str, r: Result<Registration>) -> std::result::Result<(), String> {
    match r {
        Err(e) => Err(format!("{name}: refused: {e}")),
        Ok(r) => {
            let gate_skips: Vec<_> = r
                .skipped
                .iter()
                .filter(|s| s.reason.contains("misnumbered"))
                .collect();
            if !gate_skips.is_empty() || r.questionable() {
                return Err(format!("{name}: teeth refused: {gate_skips:?}"));
            }
            Ok(())
        }
    }
}

#[test]
fn no_false_alarm_on_21_phantom_jaws() {
    let jaws = valid_jaws();
    assert!(jaws.len() >= 20);
    let mut failures = Vec::new();
    for (name, j) in &jaws {
        let r = register(&j.crowns, &j.cbct, &RegisterOptions::default());
        if let Err(f) = no_false_alarm(name, r) {
            failures.push(f);
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

fn foreign_dir() -> Option<PathBuf> {
    let d = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/foreign");
    let d = if d.exists() {
        d
    } else {
        PathBuf::from("/work/shared/data/foreign")
    };
    if d.join("f901_upper/ios.ply").exists() {
        Some(d)
    } else {
        eprintln!("skipping: the foreign jaws are not at {}", d.display());
        None
    }
}

#[test]
fn no_false_alarm_on_the_foreign_jaws() {
    let Some(dir) = foreign_dir() else { return };
    for case in ["f901_upper", "f902_lower"] {
        let ios = toothfuse::io::read_mesh(dir.join(case).join("ios.ply")).expect("IOS");
        let crowns = toothfuse::fuse::ios_crowns(&ios).expect("crowns");
        let cbct = toothfuse::io::read_teeth_with(
            dir.join(case).join("cbct.ply"),
            toothfuse::io::LabelScheme::Fdi,
        )
        .expect("CBCT");
        let r = register(&crowns, &cbct, &RegisterOptions::default());
        no_false_alarm(case, r).unwrap();
    }
}

#[test]
fn accept_questionable_registers_and_carries_the_flag() {
    let (i, c, _) = case(Kind::Swapped, 3);
    let opts = RegisterOptions {
        accept_questionable: true,
        ..RegisterOptions::default()
    };
    let r = register(&i, &c, &opts).expect("accepted");
    assert!(r.questionable());
    assert!(r.skipped.iter().all(|s| !s.reason.contains("misnumbered")));
    let json: serde_json::Value = serde_json::from_str(&r.to_json()).unwrap();
    assert_eq!(json["questionable"], true);
    let findings = json["questionable_findings"].as_array().unwrap();
    assert!(
        findings
            .iter()
            .any(|f| f.as_str().unwrap().contains("swapped")),
        "{findings:?}"
    );
    let warned = r
        .teeth
        .values()
        .filter(|t| t.warnings.iter().any(|w| w.contains("misnumbered")))
        .count();
    assert_eq!(warned, 2);
}

// ---- the C ABI: one seed of every kind, status and message (the rows of docs/errors.md) ----

fn flat(m: &TriMesh) -> (Vec<f64>, Vec<u32>) {
    (
        m.positions.iter().flat_map(|q| q.to_array()).collect(),
        m.triangles.iter().flatten().copied().collect(),
    )
}

/// Merges teeth into one mesh with per-vertex FDI labels.
fn labeled(t: &Teeth) -> (TriMesh, Vec<i32>) {
    let mut m = TriMesh::default();
    let mut l = Vec::new();
    for (&f, x) in t {
        m.append(x);
        l.extend(std::iter::repeat_n(i32::from(f), x.positions.len()));
    }
    (m, l)
}

fn add_jaw(s: &ffi_common::Session, modality: toothfuse_modality, t: &Teeth) -> toothfuse_status {
    let (m, labels) = labeled(t);
    let (v, tri) = flat(&m);
    // SAFETY: buffers sized as announced.
    unsafe {
        toothfuse_session_add_jaw(
            s.0,
            modality,
            v.as_ptr().cast(),
            v.len() / 3,
            24,
            TOOTHFUSE_SCALAR_FLOAT64,
            tri.as_ptr(),
            tri.len(),
            labels.as_ptr(),
            labels.len(),
            TOOTHFUSE_LABEL_DOMAIN_VERTEX,
        )
    }
}

#[test]
fn c_abi_names_every_kind() {
    let seed = 2;
    for kind in KINDS {
        let (i, c, e) = case(kind, seed);
        let s = ffi_common::Session::new();
        // Units are judged on entry where the jaw alone shows them, else at registration.
        let mut st = add_jaw(&s, TOOTHFUSE_MODALITY_IOS, &i);
        if st == toothfuse_status::Ok {
            st = add_jaw(&s, TOOTHFUSE_MODALITY_CBCT, &c);
        }
        if st == toothfuse_status::Ok {
            // SAFETY: live session, default options.
            st = unsafe { toothfuse_session_register(s.0, std::ptr::null()) };
        }
        let msg = s.error();
        match &e {
            Expect::Refused(k, words) => {
                assert_eq!(st, toothfuse_status::from(*k), "{kind:?}: {msg}");
                assert!(words.iter().all(|w| msg.contains(w)), "{kind:?}: {msg}");
            }
            Expect::Skipped(teeth, words) => {
                assert_eq!(st, toothfuse_status::Ok, "{kind:?}: {msg}");
                let mut n = 0usize;
                // SAFETY: live session, valid out pointer.
                unsafe { toothfuse_session_skipped_count(s.0, &mut n) };
                let mut found = Vec::new();
                for k in 0..n {
                    let (mut f, mut r) = (0i32, std::ptr::null());
                    // SAFETY: index in range, valid out pointers; the string is copied at once.
                    unsafe { toothfuse_session_skipped(s.0, k, &mut f, &mut r) };
                    // SAFETY: a NUL-terminated string owned by the session.
                    let r = unsafe { std::ffi::CStr::from_ptr(r) }.to_string_lossy();
                    if words.iter().all(|w| r.contains(w)) {
                        found.push(f as u8);
                    }
                }
                found.sort_unstable();
                let mut want = teeth.clone();
                want.sort_unstable();
                assert_eq!(found, want, "{kind:?}");
            }
        }
    }
}

#[test]
fn c_abi_unit_checks_on_entry_and_the_override_flag() {
    let p = phantom(2, Jaw::Upper, Variant::Full);
    let s = ffi_common::Session::new();
    // One tooth in metres: refused on entry, whatever else is held.
    let (v, t) = flat(&scaled(&p.cbct, 0.001)[&11]);
    let st = s.add(TOOTHFUSE_MODALITY_CBCT, 11, &v, &t);
    assert_eq!(st, toothfuse_status::UnitMismatch, "{}", s.error());
    assert!(
        s.error().contains("CBCT") && s.error().contains("metres"),
        "{}",
        s.error()
    );
    // A jaw in micrometres: refused on entry.
    let st = add_jaw(&s, TOOTHFUSE_MODALITY_IOS, &scaled(&p.crowns, 1000.0));
    assert_eq!(st, toothfuse_status::UnitMismatch, "{}", s.error());
    assert!(
        s.error().contains("IOS") && s.error().contains("micrometres"),
        "{}",
        s.error()
    );
    // Swapped labels accepted with the override: the report carries the flag.
    let (i, c, _) = case(Kind::Swapped, 2);
    assert_eq!(
        add_jaw(&s, TOOTHFUSE_MODALITY_IOS, &i),
        toothfuse_status::Ok
    );
    assert_eq!(
        add_jaw(&s, TOOTHFUSE_MODALITY_CBCT, &c),
        toothfuse_status::Ok
    );
    let o = toothfuse_options {
        accept_questionable: 1,
        ..toothfuse_options::default()
    };
    // SAFETY: live session, valid options.
    let st = unsafe { toothfuse_session_register(s.0, &o) };
    assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    let mut len = 0usize;
    // SAFETY: size query.
    unsafe { toothfuse_session_report_json(s.0, std::ptr::null_mut(), 0, &mut len) };
    len += 1; // the terminating NUL
    let mut buf = vec![0u8; len];
    // SAFETY: buffer of the queried size.
    let st = unsafe { toothfuse_session_report_json(s.0, buf.as_mut_ptr().cast(), len, &mut len) };
    assert_eq!(st, toothfuse_status::Ok, "{}", s.error());
    let text = String::from_utf8_lossy(&buf)
        .trim_end_matches('\0')
        .to_string();
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(json["questionable"], true, "{text}");
}

// ---- the CLI: one seed of every kind; exit status and the one-line message ----

fn write_teeth(path: &Path, t: &Teeth) {
    let (m, l) = labeled(t);
    toothfuse::io::write_mesh(path, &m, &[("label", &l)]).expect("write");
}

#[test]
fn cli_refuses_and_names_every_kind() {
    let seed = 3;
    let dir = std::env::temp_dir().join(format!("toothfuse_wrong_data_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for kind in KINDS {
        let (i, c, e) = case(kind, seed);
        let (ip, cp) = (dir.join("ios.ply"), dir.join("cbct.ply"));
        write_teeth(&ip, &i);
        write_teeth(&cp, &c);
        let sub = if matches!(e, Expect::Skipped(..)) {
            "register"
        } else {
            "fuse"
        };
        let out = dir.join("out");
        let o = Command::new(env!("CARGO_BIN_EXE_toothfuse"))
            .args([
                sub,
                "--ios",
                ip.to_str().unwrap(),
                "--cbct",
                cp.to_str().unwrap(),
            ])
            .args(if sub == "fuse" {
                vec!["--out", out.to_str().unwrap()]
            } else {
                vec![]
            })
            .output()
            .expect("run toothfuse");
        let (stdout, stderr) = (
            String::from_utf8_lossy(&o.stdout).to_string(),
            String::from_utf8_lossy(&o.stderr).to_string(),
        );
        match &e {
            Expect::Refused(_, words) => {
                assert!(!o.status.success(), "{kind:?}: exit 0\n{stdout}");
                // One error line (after the notes on how each input's labels were read).
                let errors: Vec<&str> = stderr
                    .lines()
                    .filter(|l| l.starts_with("toothfuse: error: "))
                    .collect();
                assert_eq!(errors.len(), 1, "{kind:?}: {stderr}");
                assert!(stderr.trim_end().ends_with(errors[0]), "{kind:?}: {stderr}");
                assert!(
                    words.iter().all(|w| stderr.contains(w)),
                    "{kind:?}: {stderr}"
                );
            }
            Expect::Skipped(teeth, words) => {
                assert!(o.status.success(), "{kind:?}: {stderr}");
                let json: serde_json::Value = serde_json::from_str(&stdout).expect("report");
                for t in teeth {
                    let s = json["skipped"]
                        .as_array()
                        .unwrap()
                        .iter()
                        .find(|s| s["fdi"] == *t)
                        .unwrap_or_else(|| panic!("{kind:?}: {t} not skipped: {stdout}"));
                    let r = s["reason"].as_str().unwrap();
                    assert!(words.iter().all(|w| r.contains(w)), "{r}");
                }
            }
        }
    }
    // The override: the swapped pair registered anyway, the report flagged.
    let (i, c, _) = case(Kind::Swapped, seed);
    write_teeth(&dir.join("ios.ply"), &i);
    write_teeth(&dir.join("cbct.ply"), &c);
    let o = Command::new(env!("CARGO_BIN_EXE_toothfuse"))
        .args(["register", "--accept-questionable", "--ios"])
        .arg(dir.join("ios.ply"))
        .arg("--cbct")
        .arg(dir.join("cbct.ply"))
        .output()
        .expect("run toothfuse");
    assert!(o.status.success());
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).expect("report");
    assert_eq!(json["questionable"], true);
    let _ = std::fs::remove_dir_all(&dir);
}
