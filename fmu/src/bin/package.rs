//! `efsi-fmu-package OUT SCENE [--parameter PATH[=UNIT]] [--input NAME[=UNIT]]
//! [--output PROBE[=UNIT]] [--range NAME=MIN..MAX] …` (or `efsi-fmu-package OUT sphere` for
//! the sphere-impact FMU): check the interface against the scene ([`efsi_fmu::spec`]) and
//! write what `cargo xtask fmu` packages into the folder OUT: `fmu.ron` and `scene.ron` (the
//! FMU's `resources/`), `modelDescription-2.xml` and `-3.xml`, `index.html` and `license.txt`
//! (its `documentation/`), and `identifier` (the model identifier, which names the library).

use efsi_fmu::description;
use efsi_fmu::spec::{SPHERE, Spec};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

fn package(args: &[String]) -> Result<PathBuf, String> {
    let (out, scene, flags): (&String, PathBuf, Vec<String>) = match args {
        [out, preset] if preset == "sphere" => (
            out,
            Path::new(env!("CARGO_MANIFEST_DIR")).join("sphere_impact.ron"),
            SPHERE.iter().map(|s| s.to_string()).collect(),
        ),
        [out, scene, flags @ ..] => (out, PathBuf::from(scene), flags.to_vec()),
        _ => {
            return Err(
                "usage: efsi-fmu-package OUT SCENE [--parameter PATH[=UNIT]] [--input NAME[=UNIT]] [--output PROBE[=UNIT]] [--range NAME=MIN..MAX] … | efsi-fmu-package OUT sphere"
                    .into(),
            );
        }
    };
    let spec = Spec::from_args(&scene, &flags)?;
    let vars = spec.variables()?;
    let out = PathBuf::from(out);
    std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;
    let files = [
        ("fmu.ron", spec.to_ron()),
        ("scene.ron", spec.scene.clone()),
        ("modelDescription-2.xml", description::fmi2(&spec, &vars)),
        ("modelDescription-3.xml", description::fmi3(&spec, &vars)),
        ("index.html", description::documentation(&spec, &vars)),
        ("license.txt", description::license()),
        ("identifier", spec.identifier()),
    ];
    for (name, text) in files {
        let p = out.join(name);
        std::fs::write(&p, text).map_err(|e| format!("{}: {e}", p.display()))?;
    }
    Ok(out)
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match package(&args) {
        Ok(_) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("efsi-fmu-package: {e}");
            ExitCode::FAILURE
        }
    }
}
