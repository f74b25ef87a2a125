//! Scene files and overrides: read a scene file ([`read_file`], [`SceneOverrides::load`]), and
//! change any setting of a scene by its path, without editing the file.
//!
//! ```text
//! efsi run cases/sphere_impact.ron --set grid.nx=128 --set solid.law.parameters.G=1e6 --refine 2
//! ```
//!
//! ```no_run
//! # use efsi_core::{Scene, overrides::Override};
//! # use efsi_run::SceneOverrides;
//! let scene = Scene::load_with(
//!     "cases/sphere_impact.ron",
//!     &[Override::set("solid.law.parameters.G", 1e6), Override::set("solid.shape.radius", 0.02)],
//! )?;
//! # Ok::<(), efsi_core::SceneError>(())
//! ```
//!
//! # Paths
//!
//! A path names a setting as the scene file nests it: struct fields by name (`grid.nx`,
//! `time.steady`), fields inside an enum's variant (`solid.shape.radius` of a `Disk`,
//! `boundaries.y_max.speed` of a `MovingWall`), list and tuple elements by index
//! (`output.probes[2].at`, `solid.shape.center[1]`, `gravity.1`), map entries by key
//! (`solid.law.parameters.G`). An `Option` that holds a value (`Some(…)`) and a variant that
//! wraps one value (`Union([…])`) are looked through. The scene's aliases (`nr`, `nz`, `r`,
//! `z`, `r_min`, …; [`efsi_core::overrides::FIELD_ALIASES`]) name the same fields as their canonical names.
//!
//! A setting absent from the file, whose default applies, is inserted (with the containers it
//! needs: `numerics.projection.solver` in a scene without `numerics` inserts
//! `numerics: (projection: (solver: …))`, a law parameter not in the file inserts it into the
//! `parameters` map). Whether a missing container is a struct `( )` or a map `{ }`, and the type
//! of a missing value, are read from the scene with its defaults filled in. A stage's
//! `numerics` section that the file leaves out has no defaults in the scene (the stage owns
//! them, [`efsi_core::scene::options`]): its containers are structs and a string that is a
//! capitalised identifier is written as an enum's variant (`IncompleteCholesky`).
//!
//! # Values
//!
//! An [`OverrideValue`] is a number, a string, a boolean — what a Python caller or an FMU
//! parameter holds — or RON text (the command line's `--set PATH=VALUE`, where `VALUE` may be
//! any RON value: `Disk(center: (0, 0.05), radius: 0.02)`). The setting's current type decides
//! how it is written: a string for a string setting (`--set solid.law.name=mooney_rivlin` needs
//! no quotes), a bare identifier for an enum's unit variant (`"IncompleteCholesky"`), an integer
//! for an integer setting (a whole float such as `128.0` is accepted; `1.5` is refused).
//!
//! # Why on the RON text, not on the Rust types
//!
//! An override edits the scene's RON text — the file as written, or [`Scene::to_ron`] for a
//! scene in memory — and the result goes through the same loader as any scene file: the same
//! syntax checks, unknown-field errors and range validation, and nothing else to keep in step
//! with the scene's types. A section of the scene that a stage plugin declares and
//! deserialises itself is reached the same way as a core one, because the path is looked up in
//! the text, not in a Rust struct. The price is that the loader's errors point into rewritten
//! text, so they are attributed back: the file is parsed alone first (its own errors keep its
//! line and column), then again after each override (each must leave a scene the loader can
//! parse, so a syntax or type error is the override's just applied), and the ranges are
//! validated once after the last (a range error belongs to the last override whose path it
//! names). A message names the override (`set grid.nx=0: grid.nx: must be at least 1 cell,
//! got 0`), never a line and column of text the user did not write.
//!
//! # Refinement
//!
//! [`Override::Refine`] (`--refine F`) multiplies every grid dimension by `F` (rounded to the
//! nearest whole number of cells, at least 1) and keeps the domain: the speed/accuracy knob. It
//! is applied after the `set`s of the same call, so `--set grid.nx=100 --refine 2` gives 200.
//!
//! # Recording
//!
//! A scene keeps the overrides applied to it (`Scene::overrides`). `run.json` records them
//! with the effective scene; a checkpoint records them with the scene file's path, and a
//! resumed run applies them again to the file, so it runs the same effective scene (and still
//! refuses a file changed since).

use efsi_core::StagePlugin;
use efsi_core::overrides::{Override, OverrideValue, attribute, field_aliases};
use efsi_core::scene::options::check_sections;
use efsi_core::scene::solid::SceneSolid;
use efsi_core::scene::{Scene, SceneError};
use efsi_ron_edit::overrides::apply_sets;
use efsi_ron_edit::{Document, Path as SettingPath};
use std::path::{Path, PathBuf};

/// Overrides applied to a scene: read a scene file with them, set, refine and read its
/// settings by path (see the module docs).
pub trait SceneOverrides: Sized {
    /// Read a scene file ([`read_file`]) and validate it: [`load_with`](Self::load_with)
    /// without overrides.
    fn load(path: impl AsRef<Path>) -> Result<Self, SceneError> {
        Self::load_with(path, &[])
    }
    /// Read a scene file, apply `overrides` in order and validate the result (see the module
    /// docs). Errors in the file name its line and column; errors an override causes name the
    /// override ([`SceneError::Override`]).
    fn load_with(path: impl AsRef<Path>, overrides: &[Override]) -> Result<Self, SceneError>;
    /// Parse scene text, apply `overrides` in order and validate; `path` is used in messages.
    fn from_str_with(text: &str, path: &Path, overrides: &[Override]) -> Result<Self, SceneError>;
    /// Set the setting at `path` to `value` in this scene (see the module docs), validate the
    /// result and record the override. On error the scene is unchanged.
    fn set(&mut self, path: &str, value: impl Into<OverrideValue>) -> Result<(), SceneError>;
    /// Multiply every grid dimension by `factor` (rounded, at least one cell), keeping the
    /// domain; validate and record it. On error the scene is unchanged.
    fn refine(&mut self, factor: f64) -> Result<(), SceneError>;
    /// Apply `overrides` to this scene in order, validate the result and record them after the
    /// ones already applied. On error the scene is unchanged.
    fn apply(&mut self, overrides: &[Override]) -> Result<(), SceneError>;
    /// The value of the setting at `path` (with the scene's defaults filled in): a number, a
    /// string (an enum's unit variant by its name), a boolean, or RON text for anything else
    /// (a struct, tuple, list or `None`). What an FMU shows as a parameter's start value.
    fn get(&self, path: &str) -> Result<OverrideValue, SceneError>;
    /// [`SceneOverrides::get`] with the stages' `numerics` sections in force: a setting of a
    /// section the scene leaves out is the default of the stage among `plugins` that declares
    /// it (what a simulation of this scene runs with). A scene whose sections do not pass their
    /// checks is read as it is.
    fn get_in_force(
        &self,
        path: &str,
        plugins: &[&dyn StagePlugin],
    ) -> Result<OverrideValue, SceneError>;
}

impl SceneOverrides for Scene {
    fn load_with(path: impl AsRef<Path>, overrides: &[Override]) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        let text = read_file(path)?;
        let mut scene = Scene::from_str_with(&text, path, overrides)?;
        scene.source_dir = path.parent().map(Path::to_path_buf);
        Ok(scene)
    }

    fn from_str_with(text: &str, path: &Path, overrides: &[Override]) -> Result<Scene, SceneError> {
        let parsed = Scene::parse(text, path)?;
        let hints = with_defaults;
        // Each override's result must read as a scene, its solid section as a solid.
        let read = |text: &str| match Scene::parse(text, path) {
            Err(SceneError::Syntax { message, .. }) => Err(message),
            Ok(scene) => match scene.solid_spec() {
                Err((_, message)) => Err(message),
                Ok(_) => Ok(scene),
            },
            other => other.map_err(|e| e.to_string()),
        };
        let aliases = field_aliases(parsed.geometry);
        let mut scene =
            apply_sets(text, parsed, overrides, aliases, hints, read).map_err(|(o, message)| {
                SceneError::Override {
                    path: path.to_path_buf(),
                    setting: o.brief(),
                    message,
                }
            })?;
        for o in overrides {
            if let Override::Refine(f) = o {
                refine_grid(&mut scene, *f).map_err(|message| SceneError::Override {
                    path: path.to_path_buf(),
                    setting: o.brief(),
                    message,
                })?;
            }
        }
        scene.overrides = overrides.to_vec();
        // Positions in messages point into the text the user wrote, never the rewritten one.
        scene.locate_sections_in(text);
        // The solid's checks (the stages own the section) too: a scene loaded or changed is
        // refused at once, as for the sections the core owns.
        scene
            .validate()
            .and_then(|()| match scene.solid_spec()? {
                Some(solid) => solid.validate(&scene),
                None => Ok(()),
            })
            .map_err(|(field, message)| attribute(path, overrides, field, message))?;
        Ok(scene)
    }

    fn set(&mut self, path: &str, value: impl Into<OverrideValue>) -> Result<(), SceneError> {
        self.apply(&[Override::set(path, value)])
    }

    fn refine(&mut self, factor: f64) -> Result<(), SceneError> {
        self.apply(&[Override::Refine(factor)])
    }

    fn apply(&mut self, overrides: &[Override]) -> Result<(), SceneError> {
        let label = PathBuf::from(format!("scene `{}`", self.name));
        let mut next = Scene::from_str_with(&self.to_ron(), &label, overrides)?;
        // No position in text the user did not write.
        next.locate_sections_in("");
        next.source_dir = self.source_dir.clone();
        let mut all = std::mem::take(&mut self.overrides);
        all.extend_from_slice(overrides);
        next.overrides = all;
        *self = next;
        Ok(())
    }

    fn get(&self, path: &str) -> Result<OverrideValue, SceneError> {
        let fail = |message: String| SceneError::Override {
            path: PathBuf::from(format!("scene `{}`", self.name)),
            setting: format!("get {path}"),
            message,
        };
        let aliases = field_aliases(self.geometry);
        let setting = SettingPath::parse(path, aliases).map_err(fail)?;
        let doc = Document::parse(with_defaults(self), aliases)
            .map_err(|(_, m)| fail(format!("cannot read the scene: {m}")))?;
        doc.get(&setting)
            .map_err(fail)?
            .ok_or_else(|| fail(format!("the scene has no setting {setting}")))
    }

    fn get_in_force(
        &self,
        path: &str,
        plugins: &[&dyn StagePlugin],
    ) -> Result<OverrideValue, SceneError> {
        let mut filled = self.clone();
        match check_sections(&mut filled, plugins) {
            // A stage's setting as the settings in force record it (a default that depends
            // on the scene resolved), else as the checked scene's text holds it.
            Ok(_) => in_force_json(&filled, path).map_or_else(|| filled.get(path), Ok),
            Err(_) => self.get(path),
        }
    }
}

/// `numerics.SECTION.FIELD` of a checked scene, from its settings in force as JSON, when that
/// names a number, a flag or an enum's unit variant.
fn in_force_json(scene: &Scene, path: &str) -> Option<OverrideValue> {
    let mut parts = path.strip_prefix("numerics.")?.split('.');
    let (section, field) = (parts.next()?, parts.next()?);
    if parts.next().is_some() {
        return None;
    }
    match scene.numerics.in_force(section, field)? {
        serde_json::Value::Bool(b) => Some(OverrideValue::Bool(*b)),
        serde_json::Value::Number(n) => Some(match n.as_i64() {
            Some(i) => OverrideValue::Int(i),
            None => OverrideValue::Float(n.as_f64()?),
        }),
        serde_json::Value::String(s) => Some(OverrideValue::Str(s.clone())),
        _ => None,
    }
}

/// The largest scene file read (4 MiB): a scene is a page of text; anything larger is not one.
pub const MAX_SCENE_BYTES: u64 = 4 << 20;

/// The text of the scene file at `path`: at most [`MAX_SCENE_BYTES`] of UTF-8; anything else is
/// refused as not a scene file.
pub fn read_file(path: &Path) -> Result<String, SceneError> {
    let io = |source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    };
    // Read at most one byte past the cap: `/dev/zero` or a huge file is refused, not read.
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| {
            use std::io::Read;
            f.take(MAX_SCENE_BYTES + 1).read_to_end(&mut bytes)
        })
        .map_err(io)?;
    if bytes.len() as u64 > MAX_SCENE_BYTES {
        return Err(io(std::io::Error::other(format!(
            "larger than {} MiB: not a scene file",
            MAX_SCENE_BYTES >> 20
        ))));
    }
    String::from_utf8(bytes).map_err(|e| {
        io(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "not UTF-8 text (invalid byte at offset {})",
                e.utf8_error().valid_up_to()
            ),
        ))
    })
}

/// `scene` as RON text with the defaults of its sections filled in where the core knows them,
/// and its `solid` section's ([`efsi_core::scene::solid::Solid`]) where it reads
/// as one: what a path is read from, and the shape of a setting the file leaves out.
fn with_defaults(scene: &Scene) -> String {
    match scene.solid_spec() {
        Ok(Some(solid)) => {
            let mut filled = scene.clone();
            filled.set_solid(&solid);
            filled.to_ron()
        }
        _ => scene.to_ron(),
    }
}

fn refine_grid(scene: &mut Scene, f: f64) -> Result<(), String> {
    if !(f.is_finite() && f > 0.0) {
        return Err(format!(
            "the factor must be a finite number > 0, got {}",
            efsi_core::scene::num(f)
        ));
    }
    let scale = |n: usize| ((n as f64) * f).round().clamp(1.0, 1e15) as usize;
    scene.grid.nx = scale(scene.grid.nx);
    scene.grid.ny = scale(scene.grid.ny);
    scene.grid.nz = scene.grid.nz.map(scale);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_are_read_by_path_with_their_defaults() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../cases/sphere_impact.ron");
        let scene = Scene::load(&path).unwrap();
        let get = |p: &str| scene.get(p).unwrap();
        assert_eq!(get("grid.nr"), OverrideValue::Int(82));
        assert_eq!(get("solid.shape.radius"), OverrideValue::Float(0.0192));
        assert_eq!(get("solid.shape.center[1]"), OverrideValue::Float(0.0573));
        assert_eq!(get("solid.velocity[1]"), OverrideValue::Float(-1.22));
        assert_eq!(get("gravity.1"), OverrideValue::Float(-9.81));
        assert_eq!(
            get("solid.law.name"),
            OverrideValue::Str("neo_hookean".into())
        );
        assert_eq!(get("solid.law.parameters.G"), OverrideValue::Float(0.18e6));
        // A default the file leaves out, an enum's unit variant, a struct.
        assert_eq!(get("time.cfl"), OverrideValue::Float(0.4));
        assert_eq!(get("geometry"), OverrideValue::Str("Axisymmetric".into()));
        assert!(matches!(get("grid"), OverrideValue::Ron(_)));
        let e = scene.get("solid.law.parameters.K").unwrap_err().to_string();
        assert!(e.contains("no setting solid.law.parameters.K"), "{e}");
        assert!(scene.get("grid..nx").is_err());
    }

    const SPHERE: &str = r#"// a comment (with a paren
Scene(
    name: "sphere",
    geometry: Axisymmetric,
    domain: (r: (0.0, 0.045), z: (0.0, 0.09)),
    grid: (nr: 23, nz: 47), /* cells */
    time: (end: 0.01, cfl: 0.4),
    fluid: (density: 1.2, viscosity: 1.8e-5),
    gravity: (0.0, -9.81),
    solid: (
        shape: Disk(center: (0.0, 0.0573), radius: 0.0192),
        density: 1106.0,
        law: (name: "neo_hookean"),
    ),
    boundaries: (r_min: Axis, r_max: NoSlip, z_min: NoSlip, z_max: NoSlip),
    output: (probes: [SolidCentroid, KineticEnergy, Point(name: "p0", field: "p", at: (0.01, 0.01))]),
)"#;

    fn with(overrides: &[Override]) -> Result<Scene, SceneError> {
        Scene::from_str_with(SPHERE, Path::new("sphere.ron"), overrides)
    }

    fn ron(p: &str, v: &str) -> Override {
        Override::set(p, OverrideValue::Ron(v.into()))
    }

    #[test]
    fn sets_reach_every_kind_of_setting() {
        let s = with(&[
            ron("grid.nx", "64"),
            Override::set("grid.nz", 96),
            Override::set("solid.shape.radius", 0.02),
            Override::set("solid.shape.center[1]", 0.06),
            ron("output.probes[2].at", "(0.02, 0.03)"),
            Override::set("gravity.1", -1.0),
            ron("solid.law.name", "mooney_rivlin"),
        ])
        .unwrap();
        assert_eq!((s.grid.nx, s.grid.ny), (64, 96));
        assert_eq!(
            s.get("solid.shape.radius").unwrap(),
            OverrideValue::Float(0.02)
        );
        assert_eq!(
            s.get("solid.shape.center").unwrap(),
            OverrideValue::Ron("(0.0, 0.06)".into())
        );
        assert!(
            s.output.text().contains("at: (0.02, 0.03)"),
            "{}",
            s.output.text()
        );
        assert_eq!(s.gravity, (0.0, -1.0));
        assert_eq!(
            s.solid_spec().unwrap().unwrap().law.unwrap().name,
            "mooney_rivlin"
        );
        assert_eq!(s.overrides.len(), 7);
        // A later override reaches inside what an earlier one set.
        let s = with(&[
            ron("initial_velocity", "Uniform((1.0, 0.0))"),
            Override::set("initial_velocity[1]", 2.0),
            ron(
                "solid.shape",
                "Rectangle(min: (0.0, 0.01), max: (0.01, 0.03))",
            ),
            Override::set("solid.shape.max[1]", 0.04),
        ])
        .unwrap();
        assert!(matches!(
            s.initial_velocity,
            efsi_core::scene::InitialVelocity::Uniform((1.0, 2.0))
        ));
        let OverrideValue::Ron(shape) = s.get("solid.shape").unwrap() else {
            panic!("{:?}", s.get("solid.shape"))
        };
        assert!(shape.starts_with("Rectangle("), "{shape}");
        assert_eq!(
            s.get("solid.shape.max[1]").unwrap(),
            OverrideValue::Float(0.04)
        );
        assert_eq!(
            s.get("solid.shape.min").unwrap(),
            OverrideValue::Ron("(0.0, 0.01)".into())
        );
    }

    #[test]
    fn absent_settings_are_inserted_with_their_containers() {
        let s = with(&[
            // A map key (the law's parameters are not in the file).
            ron("solid.law.parameters.G", "1e6"),
            Override::set("solid.law.parameters.K", 2),
            // A whole section absent, down to an enum value given as a string.
            Override::set("numerics.projection.solver", "IncompleteCholesky"),
            ron("numerics.projection.tolerance", "1e-9"),
            // An absent optional value, and an absent real given as an integer.
            ron("time.steady", "1e-6"),
            Override::set("solid.viscosity", 2),
        ])
        .unwrap();
        let law = s.solid_spec().unwrap().unwrap().law.unwrap();
        assert_eq!(law.parameters["G"], 1e6);
        assert_eq!(law.parameters["K"], 2.0);
        // A stage's section holds what the overrides wrote; the absent enum value given as a
        // string is written as its variant.
        assert_eq!(
            s.numerics.section("projection"),
            Some("(solver: IncompleteCholesky, tolerance: 1e-9)")
        );
        assert_eq!(s.time.steady, Some(1e-6));
        assert_eq!(s.solid_spec().unwrap().unwrap().viscosity, Some(2.0));
    }

    #[test]
    fn refine_scales_the_grid_after_the_sets() {
        let s = with(&[Override::Refine(1.5)]).unwrap();
        assert_eq!((s.grid.nx, s.grid.ny), (35, 71)); // 34.5 → 35, 70.5 → 71
        assert_eq!(s.domain.x, (0.0, 0.045));
        let s = with(&[Override::Refine(2.0), ron("grid.nr", "10")]).unwrap();
        assert_eq!((s.grid.nx, s.grid.ny), (20, 94));
    }

    fn refused(overrides: &[Override], needles: &[&str]) {
        let e = with(overrides).unwrap_err();
        let msg = e.to_string();
        assert!(matches!(e, SceneError::Override { .. }), "{msg}");
        assert!(msg.starts_with("sphere.ron: "), "{msg}");
        for n in needles {
            assert!(msg.contains(n), "expected `{n}` in: {msg}");
        }
        // Never a line:column of the rewritten text.
        assert!(
            !msg.starts_with("sphere.ron:") || msg.starts_with("sphere.ron: "),
            "{msg}"
        );
    }

    #[test]
    fn unknown_paths_are_refused_naming_the_override() {
        refused(&[ron("grid.nxx", "3")], &["set grid.nxx=3", "nxx", "nx"]);
        refused(
            &[ron("physics.convection", "false")],
            &["set physics.convection", "convection"],
        );
        refused(
            &[ron("output.probes[9].at", "(0, 0)")],
            &["output.probes has 3 elements, no [9]"],
        );
        refused(&[ron("grid.nx.n", "3")], &["grid.nx is an integer"]);
        refused(&[ron("grid[0]", "3")], &["grid is a struct"]);
        refused(
            &[ron("initial_velocity.x", "3")],
            &["set initial_velocity.x=3"],
        );
        refused(&[ron("a..b", "3")], &["bad path"]);
    }

    #[test]
    fn wrong_types_are_refused_naming_the_override() {
        refused(
            &[ron("fluid.viscosity", "true")],
            &["set fluid.viscosity=true", "float"],
        );
        refused(
            &[Override::set("fluid.viscosity", true)],
            &["expected a number"],
        );
        refused(
            &[ron("grid.nx", "1.5")],
            &["set grid.nx=1.5", "expected an integer"],
        );
        refused(
            &[Override::set("grid.nx", 1.5)],
            &["expected an integer, got 1.5"],
        );
        refused(&[ron("grid.nx", "many")], &["set grid.nx=many"]);
        refused(
            &[ron("solid.shape", "Disk(radius: 1.0)")],
            &["set solid.shape=", "center"],
        );
        refused(
            &[ron("boundaries.z_max", "Sticky")],
            &["set boundaries.z_max=Sticky", "Sticky"],
        );
        refused(&[ron("time.end", "(1")], &["not RON"]);
        // The second of two overrides is the one named.
        refused(
            &[ron("grid.nx", "30"), ron("fluid.density", "\"heavy\"")],
            &["set fluid.density=\"heavy\""],
        );
    }

    #[test]
    fn out_of_range_values_go_through_validation() {
        refused(
            &[ron("grid.nx", "0")],
            &["set grid.nx=0: grid.nx: must be at least 1 cell"],
        );
        refused(
            &[Override::set("solid.shape.radius", -1.0)],
            &[
                "set solid.shape.radius=-1.0: solid.shape.radius: Disk: radius must be finite and > 0, got -1",
            ],
        );
        refused(
            &[Override::set("time.cfl", 2.0)],
            &["time.cfl: must be in (0, 1]"],
        );
        refused(&[Override::Refine(0.0)], &["refine 0: the factor must be"]);
        refused(
            &[Override::Refine(1e4)],
            &["refine 10000: grid: more than 1e8 cells"],
        );
        // A file error is still the file's, with its line and column.
        let bad = SPHERE.replace("cfl: 0.4", "cfl: 0.4 0.5");
        let e = Scene::from_str_with(&bad, Path::new("sphere.ron"), &[ron("grid.nx", "3")])
            .unwrap_err();
        assert!(e.to_string().starts_with("sphere.ron:7:"), "{e}");
    }

    #[test]
    fn a_scene_in_memory_takes_sets_and_keeps_them() {
        let mut s = with(&[]).unwrap();
        s.set("solid.law.parameters.G", 3e5).unwrap();
        s.refine(2.0).unwrap();
        assert_eq!(
            s.solid_spec()
                .unwrap()
                .unwrap()
                .law
                .as_ref()
                .unwrap()
                .parameters["G"],
            3e5
        );
        assert_eq!((s.grid.nx, s.grid.ny), (46, 94));
        assert_eq!(s.overrides.len(), 2);
        let e = s.set("grid.nx", 0).unwrap_err();
        assert!(
            e.to_string().contains("scene `sphere`: set grid.nx=0"),
            "{e}"
        );
        assert_eq!(s.grid.nx, 46);
        assert_eq!(s.overrides.len(), 2);
        // Setting a None: the whole value first, then inside it.
        s.set("time.dt_max", 1e-3).unwrap();
        assert_eq!(s.time.dt_max, Some(1e-3));
    }

    #[test]
    fn every_alias_names_its_field() {
        for (alias, field) in efsi_core::overrides::FIELD_ALIASES {
            let scene = if ["r", "z"].contains(alias) {
                format!("domain.{alias}")
            } else if alias.starts_with('n') {
                format!("grid.{alias}")
            } else {
                format!("boundaries.{alias}")
            };
            let value = match *alias {
                "r" => "(0.0, 0.05)",
                "z" => "(0.0, 0.1)",
                "nr" | "nz" => "30",
                "r_min" => "Axis",
                _ => "FreeSlip",
            };
            let s = with(&[ron(&scene, value)]).unwrap_or_else(|e| panic!("{alias}: {e}"));
            let got = serde_json::to_value(&s).unwrap();
            let section = scene.split('.').next().unwrap();
            let expect: serde_json::Value = if value.starts_with(char::is_alphabetic) {
                serde_json::json!(value)
            } else {
                ron::from_str::<ron::Value>(value)
                    .ok()
                    .and_then(|v| serde_json::to_value(v).ok())
                    .unwrap()
            };
            assert_eq!(got[section][field], expect, "{alias} → {field}");
        }
    }
}
