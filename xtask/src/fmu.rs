//! `cargo xtask fmu`: package a scene as FMI 2.0 and 3.0 Co-Simulation FMUs.

use crate::{cargo, root, run, zip};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The shipped laws' packages and library stems, packaged beside the FMU library.
const LAWS: [(&str, &str); 3] = [
    ("efsi-law-neo-hookean", "efsi_law_neo_hookean"),
    (
        "efsi-law-saint-venant-kirchhoff",
        "efsi_law_saint_venant_kirchhoff",
    ),
    ("efsi-law-mooney-rivlin", "efsi_law_mooney_rivlin"),
];

/// The cargo profile the FMUs' libraries are built with (release code, stripped; see the
/// workspace's Cargo.toml) and its output folder under `target/`.
const FMU_PROFILE: &str = "fmu-release";

/// `cargo xtask fmu [SCENE [FLAGS…]]`: build the FMU library and the shipped laws (profile
/// [`FMU_PROFILE`]) and package the scene as `target/fmu/<name>.fmu` (FMI 2.0) and
/// `target/fmu/<name>_fmi3.fmu` (FMI 3.0); without a scene, the sphere-impact FMU. The flags
/// (`--parameter PATH[=UNIT]`, `--input NAME[=UNIT]`, `--output PROBE[=UNIT]`,
/// `--range NAME=MIN..MAX`) are checked against the scene by `efsi-fmu-package`. Returns the
/// two FMUs' paths.
pub(crate) fn fmu(args: &[String]) -> Result<[PathBuf; 2], String> {
    let mut c = cargo();
    c.args([
        "build",
        "--quiet",
        "--profile",
        FMU_PROFILE,
        "-p",
        "efsi-fmu",
    ]);
    for (package, _) in LAWS {
        c.args(["-p", package]);
    }
    run(
        c,
        "build the FMU library and the shipped laws (stripped release)",
    )?;
    let release = root().join("target").join(FMU_PROFILE);
    let dir = root().join("target/fmu");
    let staging = dir.join(".staging");
    let _ = std::fs::remove_dir_all(&staging);
    let mut c = Command::new(release.join("efsi-fmu-package"));
    c.arg(&staging);
    if args.is_empty() {
        c.arg("sphere");
    } else {
        c.args(args);
    }
    run(c, "check the FMU's interface against its scene")?;
    let identifier = String::from_utf8(read(&staging.join("identifier"))?)
        .map_err(|_| "identifier: not UTF-8".to_string())?;
    let library = read(&release.join("libefsi_fmu.so"))?;
    let mut files = vec![(String::new(), library)];
    for (_, stem) in LAWS {
        let name = format!("lib{stem}.so");
        let data = read(&release.join(&name))?;
        files.push((name, data));
    }
    let mut made = Vec::new();
    for (version, platform, file) in [
        ("2", "linux64", format!("{identifier}.fmu")),
        ("3", "x86_64-linux", format!("{identifier}_fmi3.fmu")),
    ] {
        let archive = FmuArchive {
            version,
            platform,
            identifier: &identifier,
            staging: &staging,
        };
        made.push(archive.write(&files, &dir.join(file))?);
    }
    // The reference result (FMI Cross-Check layout) beside the FMUs, where there is one.
    let compat = root().join("fmu/compat").join(&identifier);
    if let Ok(entries) = std::fs::read_dir(&compat) {
        for e in entries {
            let p = e.map_err(|e| e.to_string())?.path();
            if let Some(name) = p.file_name() {
                std::fs::copy(&p, dir.join(name)).map_err(|e| format!("{}: {e}", p.display()))?;
            }
        }
    }
    let [a, b] = <[PathBuf; 2]>::try_from(made).map_err(|_| "two FMUs".to_string())?;
    Ok([a, b])
}

/// The bytes of `p`, or an error naming it.
fn read(p: &Path) -> Result<Vec<u8>, String> {
    std::fs::read(p).map_err(|e| format!("{}: {e}", p.display()))
}

/// One FMU archive of a staged scene: its FMI version and platform folder.
struct FmuArchive<'a> {
    version: &'a str,
    platform: &'a str,
    identifier: &'a str,
    staging: &'a Path,
}

impl FmuArchive<'_> {
    /// Write the archive to `path`: the model description of its version, the `binaries` —
    /// `files`' first entry is the model library, the others the laws beside it — and the
    /// staged resources and documentation.
    fn write(&self, files: &[(String, Vec<u8>)], path: &Path) -> Result<PathBuf, String> {
        let (version, platform, identifier) = (self.version, self.platform, self.identifier);
        let file = path
            .file_name()
            .map_or_else(String::new, |f| f.to_string_lossy().into_owned());
        let mut z = zip::Zip::default();
        let mut add = |name: &str, data: &[u8]| {
            z.add(name, data)
                .map_err(|e| format!("{file}: {name}: {e}"))
        };
        let staged = |name: &str| read(&self.staging.join(name));
        add(
            "modelDescription.xml",
            &staged(&format!("modelDescription-{version}.xml"))?,
        )?;
        for (k, (name, data)) in files.iter().enumerate() {
            let name = if k == 0 {
                format!("{identifier}.so")
            } else {
                name.clone()
            };
            add(&format!("binaries/{platform}/{name}"), data)?;
        }
        add("resources/fmu.ron", &staged("fmu.ron")?)?;
        add("resources/scene.ron", &staged("scene.ron")?)?;
        add("documentation/index.html", &staged("index.html")?)?;
        add(
            "documentation/licenses/license.txt",
            &staged("license.txt")?,
        )?;
        let archive = z.finish().map_err(|e| format!("{file}: {e}"))?;
        std::fs::write(path, archive).map_err(|e| format!("{}: {e}", path.display()))?;
        let bytes = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
        eprintln!(
            "wrote {} (FMI {version}.0 Co-Simulation, {:.2} MB; library {:.2} MB)",
            path.display(),
            bytes as f64 / 1e6,
            files[0].1.len() as f64 / 1e6
        );
        Ok(path.to_path_buf())
    }
}
