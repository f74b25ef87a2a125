//! Law libraries that are not law libraries: copies of the real neo-Hookean library cut short
//! (1,000 B, 4 kB, 100 kB) or with their ELF structure corrupted, named by `efsi laws`,
//! `efsi laws --check`, `efsi check` and `efsi run`, or lying on the law search path. Each is
//! refused before the dynamic loader maps it (exit code 2, the file and the defect named), and
//! a listing skips one on the search path with a warning; nothing dies of SIGBUS or SIGSEGV.

mod common;

use common::{law_library, solid_scene, stderr, tmp};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// `efsi args…` with `$EFSI_LAW_PATH` set to `law_path`.
fn efsi_with_path(args: &[&str], law_path: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_efsi"))
        .args(args)
        .env("EFSI_LAW_PATH", law_path)
        .output()
        .expect("run efsi")
}

fn u16_at(b: &[u8], at: usize) -> usize {
    u16::from_le_bytes([b[at], b[at + 1]]) as usize
}
fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().unwrap())
}
fn u64_at(b: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(b[at..at + 8].try_into().unwrap())
}
fn put_u64(b: &mut [u8], at: usize, v: u64) {
    b[at..at + 8].copy_from_slice(&v.to_le_bytes());
}

/// The file offsets of the program headers of type `p_type` (ELF64, little-endian).
fn program_headers(b: &[u8], p_type: u32) -> Vec<usize> {
    let (phoff, phentsize, phnum) = (u64_at(b, 32) as usize, u16_at(b, 54), u16_at(b, 56));
    (0..phnum)
        .map(|k| phoff + k * phentsize)
        .filter(|&h| u32_at(b, h) == p_type)
        .collect()
}

/// The file offset of the value of the dynamic entry `tag`.
fn dynamic_entry(b: &[u8], tag: u64) -> usize {
    let dynamic = program_headers(b, 2)[0];
    let (offset, size) = (
        u64_at(b, dynamic + 8) as usize,
        u64_at(b, dynamic + 32) as usize,
    );
    (offset..offset + size)
        .step_by(16)
        .find(|&e| u64_at(b, e) == tag)
        .map(|e| e + 8)
        .unwrap_or_else(|| panic!("no dynamic entry {tag}"))
}

/// The broken copies of `good` and the defect each message must name.
fn broken_copies(good: &[u8]) -> Vec<(String, Vec<u8>, &'static str)> {
    let mut out = Vec::new();
    for n in [1_000, 4_096, 100_000] {
        out.push((
            format!("truncated_{n}"),
            good[..n].to_vec(),
            "the file is truncated",
        ));
    }
    let mut b = good.to_vec();
    b[..4].copy_from_slice(b"\0\0\0\0");
    out.push(("no_magic".into(), b, "no ELF magic number"));
    let mut b = good.to_vec();
    put_u64(&mut b, 32, 0x7fff_ffff_0000);
    out.push(("wild_phoff".into(), b, "program header table"));
    let mut b = good.to_vec();
    let load = program_headers(&b, 1)[0];
    put_u64(&mut b, load + 32, good.len() as u64 * 4);
    put_u64(&mut b, load + 40, good.len() as u64 * 4);
    out.push(("long_segment".into(), b, "(loadable) declares file bytes"));
    let mut b = good.to_vec();
    let strtab = dynamic_entry(&b, 5);
    put_u64(&mut b, strtab, 0xdead_0000_0000);
    out.push((
        "wild_strtab".into(),
        b,
        "puts the string table at address 0xdead00000000",
    ));
    let mut b = good.to_vec();
    put_u64(&mut b, 40, 0x7fff_ffff_0000);
    out.push(("wild_shoff".into(), b, "section header table"));
    let mut b = good.to_vec();
    let rela = dynamic_entry(&b, 7);
    let first = u64_at(&b, rela) as usize;
    // The first RELA entry's target, far outside the library (its file offset: the table's
    // address maps to the same offset in a library whose first segment starts at 0).
    put_u64(&mut b, first, 0x7fff_0000_0000);
    out.push((
        "wild_relocation".into(),
        b,
        "writes to address 0x7fff00000000, outside every loadable segment",
    ));
    out
}

#[test]
fn broken_law_libraries_are_refused_by_name_and_skipped_on_the_search_path() {
    let dir = tmp("broken-laws");
    let good_path = law_library("efsi_law_neo_hookean");
    let good = std::fs::read(&good_path).unwrap();
    assert!(good.len() > 100_000, "{} bytes", good.len());
    for (name, bytes, defect) in broken_copies(&good) {
        let lib: PathBuf = dir.join(format!("libbroken_{name}.so"));
        std::fs::write(&lib, &bytes).unwrap();
        let lib_s = lib.to_str().unwrap();
        let why = format!("{lib_s} is not a loadable library: ");

        // Described, checked, loaded for a scene and a run: refused, exit code 2.
        for args in [vec!["laws", lib_s], vec!["laws", "--check", lib_s]] {
            let o = common::efsi(&args);
            let err = stderr(&o);
            assert_eq!(o.status.code(), Some(2), "{name} {args:?}: {err}");
            assert!(err.contains(&why) && err.contains(defect), "{name}: {err}");
        }
        let scene = dir.join(format!("{name}.ron"));
        std::fs::write(&scene, solid_scene(lib_s, "\"G\": 1e4")).unwrap();
        let out = dir.join(format!("out_{name}"));
        for args in [
            vec!["check", scene.to_str().unwrap()],
            vec![
                "run",
                scene.to_str().unwrap(),
                "-q",
                "--out",
                out.to_str().unwrap(),
            ],
        ] {
            let o = common::efsi(&args);
            let err = stderr(&o);
            assert_eq!(o.status.code(), Some(2), "{name} {args:?}: {err}");
            assert!(
                err.contains("solid.law") && err.contains(&why) && err.contains(defect),
                "{name}: {err}"
            );
        }

        // On the search path under a shipped law's file name: the listing warns and goes on.
        let path_dir = dir.join(format!("path_{name}"));
        std::fs::create_dir_all(&path_dir).unwrap();
        let shipped = path_dir.join("libefsi_law_broken.so");
        std::fs::write(&shipped, &bytes).unwrap();
        for args in [vec!["laws"], vec!["laws", "--check"]] {
            let o = efsi_with_path(&args, &path_dir);
            let (out, err) = (String::from_utf8_lossy(&o.stdout), stderr(&o));
            assert_eq!(o.status.code(), Some(0), "{name} {args:?}: {out}{err}");
            assert!(
                err.contains(&format!(
                    "warning: skipped law `{}`: {} is not a loadable library: ",
                    shipped.display(),
                    shipped.display()
                )) && err.contains(defect),
                "{name}: {err}"
            );
            assert!(out.contains("neo_hookean"), "{name}: {out}");
        }
        // A scene naming it as a shipped law is refused the same way.
        let scene = dir.join(format!("{name}_shipped.ron"));
        std::fs::write(&scene, solid_scene("broken", "")).unwrap();
        let o = efsi_with_path(&["check", scene.to_str().unwrap()], &path_dir);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{name}: {err}");
        assert!(err.contains(defect), "{name}: {err}");
    }
}
