//! What a scene FMU is: an efsi scene and the interface chosen for it when it was packaged
//! (`cargo xtask fmu SCENE --parameter PATH[=UNIT] … --input NAME[=UNIT] … --output
//! PROBE[=UNIT] … --range NAME=MIN..MAX …`), carried in the FMU as `resources/fmu.ron`.
//!
//! - **Parameters** are scene settings by their path, with the syntax of `efsi run --set`
//!   ([`efsi_core::overrides`]): `solid.law.parameters.G`, `boundaries.y_max.speed`,
//!   `solid.shape.center[1]`. Their start values are the scene's; they are applied as overrides
//!   to the scene when initialisation ends, so a bad value is refused by the scene loader's own
//!   checks, naming the setting.
//! - **Inputs** are the settings a running simulation takes between steps: `base_acceleration`
//!   (the grid frame's acceleration along y — z in axisymmetric scenes —; the body force becomes
//!   gravity − a) and `boundaries.<side>.speed` of a moving wall.
//! - **Outputs** are the scene's probe columns (`efsi run`'s `probes.csv` header), by name; with
//!   no `--output`, all of them.
//! - [`REFINE`] (`--parameter refine`) is the one parameter that is not a setting: the grid's
//!   refinement factor (`efsi run --refine F`, [`Override::Refine`]), start value 1 — the
//!   speed/accuracy knob, applied after the settings.
//! - `max_solver_steps_per_step` (the bound on work per communication step) and the solver
//!   step count `steps` are always there.
//!
//! The variables and their value references are derived from the spec
//! ([`Spec::variables`]); the instantiation token is a hash of the spec (scene text included)
//! and the crate version.

use efsi_core::Scene;
use efsi_core::overrides::{Override, OverrideValue};
use efsi_core::scene::{Boundary, Side};
use efsi_run::SceneOutput;
use efsi_run::SceneOverrides;
use efsi_stages::solid::SceneSolid;
use serde::{Deserialize, Serialize};
use std::fmt::Write;
use std::path::Path;

/// The type of a model variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Kind {
    /// A real number (FMI 2.0 `Real`, FMI 3.0 `Float64`).
    Real,
    /// A 32-bit integer (FMI 2.0 `Integer`, FMI 3.0 `Int32`).
    Int32,
    /// A count (FMI 2.0 `Integer`, saturated; FMI 3.0 `Int64`).
    Int64,
    /// A string.
    String,
}

/// The causality of a model variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Causality {
    /// Time.
    Independent,
    /// Set before initialisation, fixed afterwards.
    Parameter,
    /// Set by the importer at any time.
    Input,
    /// Computed by the model.
    Output,
}

/// `x` as a short decimal: plain (`0.045`, `1000`) when that takes at most 12 characters, else
/// scientific (`5e-324`, `1e13`), so that a declared bound such as the smallest double above 0
/// reads as one.
pub fn short(x: f64) -> String {
    let plain = format!("{x}");
    if plain.len() <= 12 {
        plain
    } else {
        format!("{x:e}")
    }
}

/// One variable of the model description.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Variable {
    /// Value reference.
    pub vr: u32,
    /// Name (a scene path, an input's name or a probe column).
    pub name: String,
    /// Type.
    pub kind: Kind,
    /// Causality.
    pub causality: Causality,
    /// Unit, if any.
    pub unit: Option<String>,
    /// Start value as written in the model description (parameters and inputs).
    pub start: Option<String>,
    /// The smallest value accepted (inclusive), if bounded below.
    pub min: Option<f64>,
    /// The largest value accepted (inclusive), if bounded above.
    pub max: Option<f64>,
    /// Description.
    pub description: String,
}

impl Variable {
    /// Refuse `value` outside `[min, max]` (or not finite): the message names the variable,
    /// the value and the range.
    pub fn check_range(&self, value: f64) -> Result<(), String> {
        let inside = value.is_finite()
            && self.min.is_none_or(|m| value >= m)
            && self.max.is_none_or(|m| value <= m);
        if inside {
            return Ok(());
        }
        let unit = self
            .unit
            .as_deref()
            .map_or(String::new(), |u| format!(" {u}"));
        let bound = |b: Option<f64>| b.map_or("unbounded".to_string(), short);
        Err(format!(
            "{} `{}` = {value}{unit}: outside its range [{}, {}]{unit}",
            match self.causality {
                Causality::Input => "input",
                _ => "parameter",
            },
            self.name,
            bound(self.min),
            bound(self.max),
        ))
    }
}

/// A parameter, input or output as packaged.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Port {
    /// Its name: a scene path, an input name, a probe column.
    pub name: String,
    /// Its unit, if given.
    pub unit: Option<String>,
    /// The range accepted (`--range`), if given.
    pub range: (Option<f64>, Option<f64>),
}

impl Port {
    /// A port called `name`, without unit or range.
    fn named(name: &str) -> Port {
        Port {
            name: name.to_string(),
            unit: None,
            range: (None, None),
        }
    }
}

/// A scene FMU's definition (see the module docs).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Spec {
    /// The model's name and identifier (the scene's name).
    pub name: String,
    /// The scene as packaged (RON text).
    pub scene: String,
    /// Parameters: scene paths.
    pub parameters: Vec<Port>,
    /// Inputs.
    pub inputs: Vec<Port>,
    /// Outputs: probe columns.
    pub outputs: Vec<Port>,
}

/// The variable of parameter `p` at value reference `vr`: its kind and start from the scene.
fn parameter_variable(scene: &Scene, vr: u32, p: &Port) -> Result<Variable, String> {
    let (kind, start) = match scene_value(scene, &p.name)? {
        OverrideValue::Int(i) => (Kind::Int32, i.to_string()),
        OverrideValue::Float(x) => (Kind::Real, format!("{x:?}")),
        OverrideValue::Str(s) => (Kind::String, s),
        other => {
            return Err(format!(
                "parameter `{}`: {other} is not a number or a string",
                p.name
            ));
        }
    };
    Ok(Variable {
        vr,
        name: p.name.clone(),
        kind,
        causality: Causality::Parameter,
        unit: p.unit.clone(),
        start: Some(start),
        min: p.range.0,
        max: p.range.1,
        description: if p.name == REFINE {
            "Grid refinement: every grid dimension multiplied by this factor (rounded), the domain kept, as efsi run --refine".into()
        } else {
            format!("The scene setting `{}`", p.name)
        },
    })
}

/// The variable of input `i` at value reference `vr`, starting from the scene's value.
fn input_variable(scene: &Scene, vr: u32, i: &Port) -> Variable {
    let start = input_start(scene, &i.name);
    Variable {
        vr,
        name: i.name.clone(),
        kind: Kind::Real,
        causality: Causality::Input,
        unit: i.unit.clone(),
        start: Some(format!("{start:?}")),
        min: i.range.0,
        max: i.range.1,
        description: match input_target(&i.name) {
            Some(InputTarget::BaseAcceleration) => "Acceleration of the grid's frame along y (z), positive up: the body force is gravity - base_acceleration".into(),
            _ => format!("Speed of the moving wall `{}` (its profile and motion multiply it)", i.name),
        },
    }
}

/// The ports the flags name — parameters, inputs and outputs, in order — and the `--range`
/// values, unchecked.
fn parse_flags(args: &[String]) -> Result<([Vec<Port>; 3], Vec<String>), String> {
    let port = |arg: &str| {
        let (name, unit) = match arg.split_once('=') {
            Some((n, u)) => (n.trim(), Some(u.trim().to_string())),
            None => (arg.trim(), None),
        };
        Port {
            unit,
            ..Port::named(name)
        }
    };
    let mut ports: [Vec<Port>; 3] = Default::default();
    let mut ranges = Vec::new();
    let mut k = 0;
    while k < args.len() {
        let flag = args[k].as_str();
        let value = args
            .get(k + 1)
            .ok_or_else(|| format!("{flag}: a value is missing"))?;
        match flag {
            "--parameter" => ports[0].push(port(value)),
            "--input" => ports[1].push(port(value)),
            "--output" => ports[2].push(port(value)),
            "--range" => ranges.push(value.clone()),
            _ => {
                return Err(format!(
                    "unknown flag `{flag}`: expected --parameter PATH[=UNIT], --input NAME[=UNIT], --output PROBE[=UNIT], --range NAME=MIN..MAX"
                ));
            }
        }
        k += 2;
    }
    Ok((ports, ranges))
}

/// The bounds of a port's range, each optional.
type Range = (Option<f64>, Option<f64>);

/// A `--range NAME=MIN..MAX` value: the name and the bounds (`None` for an empty bound, `-inf`
/// as MIN or `inf` as MAX), checked finite and ordered.
fn parse_range(r: &str) -> Result<(&str, Range), String> {
    let (name, bounds) = r
        .split_once('=')
        .ok_or_else(|| format!("--range {r}: expected NAME=MIN..MAX"))?;
    let (lo, hi) = bounds
        .split_once("..")
        .ok_or_else(|| format!("--range {r}: expected NAME=MIN..MAX"))?;
    // A bound is a finite number; empty, `-inf` (MIN) or `inf` (MAX) for none.
    let num = |s: &str, upper: bool| -> Result<Option<f64>, String> {
        let s = s.trim();
        if s.is_empty() {
            return Ok(None);
        }
        let x: f64 = s
            .parse()
            .map_err(|_| format!("--range {r}: `{s}` is not a number"))?;
        match (x.is_nan(), x.is_infinite(), upper, x > 0.0) {
            (true, ..) => Err(format!("--range {r}: `{s}` is not a number")),
            (false, true, true, true) | (false, true, false, false) => Ok(None),
            (false, true, ..) => Err(format!(
                "--range {r}: {} cannot be {s}",
                if upper { "MAX" } else { "MIN" }
            )),
            _ => Ok(Some(x)),
        }
    };
    let range = (num(lo, false)?, num(hi, true)?);
    if let (Some(a), Some(b)) = range
        && a > b
    {
        return Err(format!("--range {r}: MIN {a} is above MAX {b}"));
    }
    Ok((name.trim(), range))
}

/// What an input acts on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum InputTarget {
    /// The frame's acceleration along y (z).
    BaseAcceleration,
    /// A moving wall's speed.
    WallSpeed(Side),
}

/// The input named `name`, if it is one (`base_acceleration`, `boundaries.<side>.speed`).
pub fn input_target(name: &str) -> Option<InputTarget> {
    if name == "base_acceleration" {
        return Some(InputTarget::BaseAcceleration);
    }
    let side = name.strip_prefix("boundaries.")?.strip_suffix(".speed")?;
    let canonical = efsi_core::overrides::FIELD_ALIASES
        .iter()
        .find(|(a, _)| *a == side)
        .map_or(side, |(_, c)| c);
    Side::ALL
        .into_iter()
        .find(|s| s.field_name() == canonical)
        .map(InputTarget::WallSpeed)
}

/// The name of the grid-refinement parameter (`--parameter refine`): every grid dimension
/// multiplied by its value, keeping the domain, after the settings are applied.
pub const REFINE: &str = "refine";

/// The value reference of the time.
pub const VR_TIME: u32 = 0;
/// The value reference of `max_solver_steps_per_step`.
pub const VR_MAX_STEPS: u32 = 1;
/// The value reference of `steps`.
pub const VR_STEPS: u32 = 3000;
const VR_PARAMETERS: u32 = 2;
const VR_INPUTS: u32 = 1000;
const VR_OUTPUTS: u32 = 2000;
/// The default bound on solver steps per communication step.
pub const DEFAULT_MAX_SOLVER_STEPS: i32 = 10_000;

impl Spec {
    /// A spec from the command line's flags, checked against the scene at `path` (which must be
    /// one a simulation accepts: its ranges and every stage's options): every
    /// parameter path exists (its start value read from the scene), every input is one the
    /// scene can take, every output a probe column of the scene, every range names one of them.
    pub fn from_args(path: &Path, args: &[String]) -> Result<Spec, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let mut scene = Scene::from_str_at(&text, path).map_err(|e| e.to_string())?;
        // The scene as a simulation checks it (its ranges, then every stage's options), so a
        // scene the FMU could not set up is refused here, not at the importer's initialisation.
        scene
            .validate()
            .map_err(|(field, message)| format!("{}: {field}: {message}", path.display()))?;
        scene
            .check_options(path, &efsi_stages::builtin())
            .map_err(|e| e.to_string())?;
        let ([parameters, inputs, outputs], ranges) = parse_flags(args)?;
        let mut spec = Spec {
            name: scene.name.clone(),
            scene: text,
            parameters,
            inputs,
            outputs,
        };
        let columns = probe_columns(&scene)?;
        if spec.outputs.is_empty() {
            spec.outputs = columns.iter().map(|c| Port::named(c)).collect();
        }
        for o in &spec.outputs {
            if !columns.contains(&o.name) {
                return Err(format!(
                    "--output {}: the scene has no probe column of that name; it has: {}",
                    o.name,
                    columns.join(", ")
                ));
            }
        }
        for p in &spec.parameters {
            scene_value(&scene, &p.name).map_err(|e| format!("--parameter {}: {e}", p.name))?;
        }
        for i in &spec.inputs {
            check_input(&scene, &i.name).map_err(|e| format!("--input {}: {e}", i.name))?;
        }
        for r in ranges {
            let (name, range) = parse_range(&r)?;
            let target = spec
                .parameters
                .iter_mut()
                .chain(spec.inputs.iter_mut())
                .find(|p| p.name == name)
                .ok_or_else(|| format!("--range {r}: no parameter or input `{name}`"))?;
            target.range = range;
        }
        for p in &mut spec.parameters {
            if p.range != (None, None) {
                p.range = declared_range(&spec.scene, path, &scene, p)?;
            }
        }
        for i in &spec.inputs {
            let start = input_start(&scene, &i.name);
            check_start(&i.name, i.range, start)?;
        }
        let mut names: Vec<&str> = spec
            .parameters
            .iter()
            .chain(&spec.inputs)
            .chain(&spec.outputs)
            .map(|p| p.name.as_str())
            .collect();
        names.sort_unstable();
        if let Some(w) = names.windows(2).find(|w| w[0] == w[1]) {
            return Err(format!("`{}` is named twice", w[0]));
        }
        Ok(spec)
    }

    /// The model identifier (the library is `binaries/<platform>/<identifier>.so`): the name
    /// with anything but letters, digits and `_` replaced by `_`.
    pub fn identifier(&self) -> String {
        self.name
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
            .collect()
    }

    /// The spec as RON (`resources/fmu.ron`).
    pub fn to_ron(&self) -> String {
        ron::ser::to_string_pretty(self, ron::ser::PrettyConfig::default()).unwrap_or_default()
    }

    /// A spec from `resources/fmu.ron`.
    pub fn from_ron(text: &str) -> Result<Spec, String> {
        ron::from_str(text).map_err(|e| format!("resources/fmu.ron: {e}"))
    }

    /// The parsed scene as packaged.
    pub fn parsed_scene(&self) -> Result<Scene, String> {
        Scene::from_str_at(&self.scene, Path::new("resources/scene.ron")).map_err(|e| e.to_string())
    }

    /// Every variable, in model-description order: time, `max_solver_steps_per_step`, the
    /// parameters, the inputs, the outputs, `steps`.
    pub fn variables(&self) -> Result<Vec<Variable>, String> {
        let scene = self.parsed_scene()?;
        let mut v = vec![
            Variable {
                vr: VR_TIME,
                name: "time".into(),
                kind: Kind::Real,
                causality: Causality::Independent,
                unit: Some("s".into()),
                start: None,
                min: None,
                max: None,
                description: "Simulation time".into(),
            },
            Variable {
                vr: VR_MAX_STEPS,
                name: "max_solver_steps_per_step".into(),
                kind: Kind::Int32,
                causality: Causality::Parameter,
                unit: None,
                start: Some(DEFAULT_MAX_SOLVER_STEPS.to_string()),
                min: Some(1.0),
                max: Some(1e9),
                description: "The most solver steps one communication step may take; a step that needs more is refused (Discard) with the state of its start kept".into(),
            },
        ];
        for (k, p) in self.parameters.iter().enumerate() {
            v.push(parameter_variable(&scene, VR_PARAMETERS + k as u32, p)?);
        }
        for (k, i) in self.inputs.iter().enumerate() {
            v.push(input_variable(&scene, VR_INPUTS + k as u32, i));
        }
        for (k, o) in self.outputs.iter().enumerate() {
            v.push(Variable {
                vr: VR_OUTPUTS + k as u32,
                name: o.name.clone(),
                kind: Kind::Real,
                causality: Causality::Output,
                unit: o.unit.clone(),
                start: None,
                min: None,
                max: None,
                description: format!(
                    "The scene's probe column `{}` (as in efsi run's probes.csv)",
                    o.name
                ),
            });
        }
        v.push(Variable {
            vr: VR_STEPS,
            name: "steps".into(),
            kind: Kind::Int64,
            causality: Causality::Output,
            unit: None,
            start: None,
            min: None,
            max: None,
            description: "Solver steps taken since the start".into(),
        });
        Ok(v)
    }

    /// The FMI 2.0 GUID and FMI 3.0 instantiation token: the 128-bit XXH3 hash of the spec
    /// and the crate version, as `{xxxxxxxx-xxxx-xxxx-xxxx-xxxxxxxxxxxx}`.
    pub fn token(&self) -> String {
        let text = format!("efsi-fmu {}\n{}", env!("CARGO_PKG_VERSION"), self.to_ron());
        let h = xxhash_rust::xxh3::xxh3_128(text.as_bytes());
        format!(
            "{{{:08x}-{:04x}-{:04x}-{:04x}-{:012x}}}",
            h >> 96,
            (h >> 80) & 0xffff,
            (h >> 64) & 0xffff,
            (h >> 48) & 0xffff,
            h & 0xffff_ffff_ffff
        )
    }

    /// The scene with the parameters' values applied (as overrides, in order).
    pub fn scene_with(&self, values: &[(String, OverrideValue)]) -> Result<Scene, String> {
        let mut overrides = Vec::with_capacity(values.len());
        for (p, v) in values {
            overrides.push(if p == REFINE {
                match v {
                    OverrideValue::Float(f) => Override::Refine(*f),
                    OverrideValue::Int(i) => Override::Refine(*i as f64),
                    other => return Err(format!("parameter `{REFINE}`: {other} is not a number")),
                }
            } else {
                Override::set(p.clone(), v.clone())
            });
        }
        Scene::from_str_with(&self.scene, Path::new("resources/scene.ron"), &overrides)
            .map_err(|e| e.to_string())
    }
}

/// The probe columns of a scene, in `probes.csv` order (time excluded).
pub fn probe_columns(scene: &Scene) -> Result<Vec<String>, String> {
    let output = scene.output_spec().map_err(|(f, m)| format!("{f}: {m}"))?;
    let bodies = efsi_run::probes::body_names(scene);
    Ok(output
        .probes
        .iter()
        .flat_map(|p| efsi_run::probes::columns(p, scene.geometry, &bodies))
        .collect())
}

/// The FMI 2 Integer's range (a 32-bit signed integer).
const INT32: (f64, f64) = (i32::MIN as f64, i32::MAX as f64);

/// Refuse a start value outside its variable's range.
fn check_start(name: &str, (lo, hi): (Option<f64>, Option<f64>), start: f64) -> Result<(), String> {
    if lo.is_some_and(|l| start < l) || hi.is_some_and(|h| start > h) {
        let bound = |b: Option<f64>, none: &str| b.map_or(none.to_string(), |b| b.to_string());
        return Err(format!(
            "--range {name}={}..{}: the start value {start} (the scene's) is outside the range",
            bound(lo, ""),
            bound(hi, "")
        ));
    }
    Ok(())
}

/// The start value of input `name` (a moving wall's speed in the scene, else 0).
fn input_start(scene: &Scene, name: &str) -> f64 {
    match input_target(name) {
        Some(InputTarget::WallSpeed(side)) => match scene.boundaries.get(side) {
            Boundary::MovingWall { speed, .. } => *speed,
            _ => 0.0,
        },
        _ => 0.0,
    }
}

/// The range parameter `p` declares: its `--range` checked against the scene (the start value
/// inside it; an Integer's bounds whole numbers within FMI 2's 32 bits), and each bound the
/// scene refuses (an open bound: `G > 0`, a radius > 0) replaced by the nearest value it
/// accepts — the next double inward — so that every value inside the declared range passes
/// `exitInitializationMode`'s checks of the scene and the law's parameter table. A bound
/// whose neighbour is refused too is an error naming it and why.
fn declared_range(
    text: &str,
    path: &Path,
    scene: &Scene,
    p: &Port,
) -> Result<(Option<f64>, Option<f64>), String> {
    let (lo, hi) = p.range;
    let shown = |b: Option<f64>| b.map_or(String::new(), |b| b.to_string());
    let flag = format!("--range {}={}..{}", p.name, shown(lo), shown(hi));
    let start = scene_value(scene, &p.name)?;
    let integer = matches!(start, OverrideValue::Int(_));
    let start = match start {
        OverrideValue::Int(i) => i as f64,
        OverrideValue::Float(x) => x,
        other => return Err(format!("{flag}: the parameter is {other}, not a number")),
    };
    if integer {
        for b in [lo, hi].into_iter().flatten() {
            if b.fract() != 0.0 || b < INT32.0 || b > INT32.1 {
                return Err(format!(
                    "{flag}: `{}` is an Integer: its bounds must be whole numbers in [{}, {}] (FMI 2's 32-bit Integer), got {b}",
                    p.name, INT32.0, INT32.1
                ));
            }
        }
    }
    check_start(&p.name, (lo, hi), start)?;
    let value = |x: f64| {
        if integer {
            OverrideValue::Int(x as i64)
        } else {
            OverrideValue::Float(x)
        }
    };
    let refused = |x: f64| accepted(text, path, &p.name, value(x)).err();
    let mut declared = (lo, hi);
    for (bound, inward, slot) in [(lo, 1.0, &mut declared.0), (hi, -1.0, &mut declared.1)] {
        let Some(b) = bound else { continue };
        let Some(why) = refused(b) else { continue };
        let next = if integer {
            b + inward
        } else if inward > 0.0 {
            b.next_up()
        } else {
            b.next_down()
        };
        if refused(next).is_some() {
            return Err(format!("{flag}: the bound {b} is refused: {why}"));
        }
        *slot = Some(next);
    }
    Ok(declared)
}

/// Whether the scene of `text` with the setting `name` = `value` passes the checks of
/// `exitInitializationMode` before the simulation is built: the scene's own and, for a law
/// parameter, the law's declared range. The error says why not.
fn accepted(text: &str, path: &Path, name: &str, value: OverrideValue) -> Result<(), String> {
    let set = if name == REFINE {
        match value {
            OverrideValue::Float(f) => Override::Refine(f),
            OverrideValue::Int(i) => Override::Refine(i as f64),
            _ => return Err("not a number".into()),
        }
    } else {
        Override::set(name.to_string(), value.clone())
    };
    let scene = Scene::from_str_with(text, path, &[set]).map_err(|e| e.to_string())?;
    let Some(param) = name.strip_prefix("solid.law.parameters.") else {
        return Ok(());
    };
    let x = match value {
        OverrideValue::Float(x) => x,
        OverrideValue::Int(i) => i as f64,
        _ => return Ok(()),
    };
    let dir = path.parent().unwrap_or(Path::new("."));
    let solid = scene.solid_spec().map_err(|(f, m)| format!("{f}: {m}"))?;
    let Some(law) = solid.and_then(|s| s.law) else {
        return Ok(());
    };
    let info = efsi_laws_host::loader::resolve_law(&law.name, dir)
        .and_then(|lib| efsi_laws_host::describe(&lib))
        .map_err(|e| e.to_string())?;
    match info.parameters.iter().find(|d| d.name == param) {
        Some(d) if !d.contains(x) => Err(format!(
            "law `{}`: {param} = {x} is outside its range {}",
            info.name,
            d.range_text()
        )),
        _ => Ok(()),
    }
}

/// The value of the setting at `path` in `scene` (with its defaults, the stages' too);
/// [`REFINE`]'s is 1.
pub fn scene_value(scene: &Scene, path: &str) -> Result<OverrideValue, String> {
    if path == REFINE {
        return Ok(OverrideValue::Float(1.0));
    }
    scene
        .get_in_force(path, &efsi_stages::builtin())
        .map_err(|e| e.to_string())
}

/// Whether the scene can take the input `name`.
fn check_input(scene: &Scene, name: &str) -> Result<(), String> {
    match input_target(name) {
        None => Err("not an input: expected base_acceleration or boundaries.<side>.speed".into()),
        Some(InputTarget::BaseAcceleration) if scene.gravity == (0.0, 0.0) => Err(
            "the frame's acceleration acts through the body force, which runs only with gravity: give the scene a gravity"
                .into(),
        ),
        Some(InputTarget::WallSpeed(side))
            if !matches!(scene.boundaries.get(side), Boundary::MovingWall { .. }) =>
        {
            let mut s = String::new();
            let _ = write!(s, "{} is not a moving wall in the scene", side.field_name());
            Err(s)
        }
        _ => Ok(()),
    }
}

/// The spec packaged with the library this code was loaded from (`resources/fmu.ron` of the
/// FMU, two folders above `binaries/<platform>/`), and a model of it when `token` is its
/// instantiation token.
pub fn packaged_model(token: &str) -> Result<crate::model::Model, String> {
    let dir = crate::stepping::library_dir()
        .ok_or("the FMU library cannot find its own folder (dladdr failed)")?;
    let path = dir
        .parent()
        .and_then(Path::parent)
        .map(|root| root.join("resources").join("fmu.ron"))
        .ok_or("the FMU library is not in binaries/<platform>/ of an FMU")?;
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let spec = Spec::from_ron(&text)?;
    if token != spec.token() {
        return Err(format!(
            "the instantiation token / GUID {token} is not this FMU's {} (a modelDescription.xml of another build?)",
            spec.token()
        ));
    }
    crate::model::Model::new(std::sync::Arc::new(spec))
}

/// The sphere-impact FMU (`cargo xtask fmu` without a scene): the scene
/// `fmu/sphere_impact.ron` and these flags.
pub const SPHERE: &[&str] = &[
    "--parameter",
    "solid.shape.radius=m",
    "--range",
    "solid.shape.radius=0..0.045",
    "--parameter",
    "solid.shape.center[1]=m",
    "--range",
    "solid.shape.center[1]=0..0.09",
    "--parameter",
    "solid.velocity[1]=m/s",
    "--range",
    "solid.velocity[1]=-100..100",
    "--parameter",
    "solid.density=kg/m3",
    "--range",
    "solid.density=1..25000",
    "--parameter",
    "solid.law.name",
    "--parameter",
    "solid.law.parameters.G=Pa",
    "--range",
    "solid.law.parameters.G=0..1e10",
    "--parameter",
    "fluid.density=kg/m3",
    "--range",
    "fluid.density=0.01..25000",
    "--parameter",
    "fluid.viscosity=Pa.s",
    "--range",
    "fluid.viscosity=0..1e4",
    "--parameter",
    "gravity.1=m/s2",
    "--range",
    "gravity.1=-100..100",
    "--parameter",
    "grid.nr",
    "--range",
    "grid.nr=2..1000",
    "--parameter",
    "grid.nz",
    "--range",
    "grid.nz=2..2000",
    "--parameter",
    "refine",
    "--range",
    "refine=0.1..10",
    "--parameter",
    "time.cfl",
    "--range",
    "time.cfl=0..1",
    "--input",
    "base_acceleration=m/s2",
    "--range",
    "base_acceleration=-1000..1000",
    "--output",
    "solid_y=m",
    "--output",
    "solid_v=m/s",
    "--output",
    "contact_force=N/rad",
    "--output",
    "contact_radius=m",
    "--output",
    "kinetic_energy=J/rad",
    "--output",
    "elastic_energy=J/rad",
];

#[cfg(test)]
mod tests {
    use super::*;

    fn args(a: &[&str]) -> Vec<String> {
        a.iter().map(|s| s.to_string()).collect()
    }

    fn sphere() -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("sphere_impact.ron")
    }

    #[test]
    fn the_sphere_spec_reads_its_start_values_from_the_scene() {
        let spec = Spec::from_args(&sphere(), &args(SPHERE)).unwrap();
        let vars = spec.variables().unwrap();
        let get = |n: &str| vars.iter().find(|v| v.name == n).unwrap().clone();
        assert_eq!(get("solid.shape.radius").start.as_deref(), Some("0.0192"));
        assert_eq!(get("grid.nr").kind, Kind::Int32);
        assert_eq!(get("grid.nr").start.as_deref(), Some("23"));
        assert_eq!(get("solid.law.name").kind, Kind::String);
        assert_eq!(get("base_acceleration").causality, Causality::Input);
        assert_eq!(
            (get("solid.velocity[1]").min, get("solid.velocity[1]").max),
            (Some(-100.0), Some(100.0))
        );
        assert_eq!(get("contact_force").causality, Causality::Output);
        // Value references are unique; the token changes with the spec.
        for (k, a) in vars.iter().enumerate() {
            assert!(
                vars[k + 1..]
                    .iter()
                    .all(|b| b.vr != a.vr && b.name != a.name)
            );
        }
        let mut other = spec.clone();
        other.outputs.pop();
        assert_ne!(other.token(), spec.token());
        assert_eq!(Spec::from_ron(&spec.to_ron()).unwrap(), spec);
    }

    /// A scene a simulation would refuse is refused when packaged, naming the setting: a stage's
    /// option out of range (the contact's friction, ten orders smaller too) and a range of the
    /// scene itself, not at the importer's initialisation.
    #[test]
    fn a_scene_a_simulation_refuses_is_refused_when_packaged() {
        let dir = std::env::temp_dir().join(format!("efsi-fmu-refuse-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let base = std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../cases/two_soft_disks.ron"),
        )
        .unwrap();
        let numerics = "numerics: (projection: (tolerance: 1e-13), elastic: (tolerance: 1e-12)),";
        assert!(base.contains(numerics));
        let with = |mu: &str| {
            format!(
                "numerics: (projection: (tolerance: 1e-13), elastic: (tolerance: 1e-12), \
                 contact: (friction: {mu})),"
            )
        };
        for (edit, what) in [
            (
                base.replace(numerics, &with("-0.5")),
                "numerics.contact.friction",
            ),
            (
                base.replace(numerics, &with("-1e-11")),
                "numerics.contact.friction",
            ),
            (base.replace("cfl: 0.4", "cfl: -0.4"), "time.cfl"),
        ] {
            assert_ne!(edit, base);
            let path = dir.join("scene.ron");
            std::fs::write(&path, &edit).unwrap();
            let e = Spec::from_args(&path, &[]).unwrap_err();
            assert!(e.contains(what), "{what}: {e}");
        }
        let path = dir.join("scene.ron");
        std::fs::write(&path, &base).unwrap();
        Spec::from_args(&path, &[]).unwrap();
        std::fs::remove_dir_all(&dir).ok();
    }

    /// A scene of several bodies (`cases/two_drops.ron`): its outputs are the probe columns
    /// named per body, and a model steps them — each drop's volume kept, the heavy drop
    /// falling farther, no overlap.
    #[test]
    fn a_scene_of_several_bodies_has_its_outputs_named_per_body() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../cases/two_drops.ron");
        let all = Spec::from_args(&path, &[]).unwrap();
        let names: Vec<&str> = all.outputs.iter().map(|o| o.name.as_str()).collect();
        assert_eq!(
            names[..7],
            [
                "light.solid_volume",
                "heavy.solid_volume",
                "light.solid_x",
                "light.solid_y",
                "heavy.solid_x",
                "heavy.solid_y",
                "light.solid_u"
            ]
        );
        assert!(names.ends_with(&[
            "max_solid_fraction_sum",
            "solid_overlap_volume",
            "light.heavy.shared_volume",
            "light.heavy.shared_cells"
        ]));
        // The single solid's column is not one of this scene's.
        let e = Spec::from_args(&path, &args(&["--output", "solid_y=m"])).unwrap_err();
        assert!(e.contains("light.solid_y"), "{e}");
        let ports = [
            "light.solid_volume=m2",
            "heavy.solid_volume=m2",
            "light.solid_y=m",
            "heavy.solid_y=m",
            "max_solid_fraction_sum=1",
        ];
        let flags: Vec<&str> = ports.iter().flat_map(|p| ["--output", *p]).collect();
        let spec = Spec::from_args(&path, &args(&flags)).unwrap();
        let mut model = crate::model::Model::new(std::sync::Arc::new(spec)).unwrap();
        model.setup_experiment(0.0, Some(1.0)).unwrap();
        model.enter_initialization();
        model.exit_initialization().unwrap();
        let read = |model: &mut crate::model::Model| -> Vec<f64> {
            (0..ports.len() as u32)
                .map(|k| model.get_real(VR_OUTPUTS + k).unwrap())
                .collect()
        };
        let start = read(&mut model);
        // Two drops of radius 0.4 (per unit depth); both at height 3.
        assert_eq!(start[0], start[1]);
        assert!(
            (start[0] - std::f64::consts::PI * 0.16).abs() < 1e-3,
            "{start:?}"
        );
        assert!((start[2] - 3.0).abs() < 1e-12 && (start[3] - 3.0).abs() < 1e-12);
        model.do_step(0.0, 0.25).unwrap();
        let now = read(&mut model);
        for k in 0..2 {
            assert!((now[k] - start[k]).abs() <= 1e-10 * start[k], "{now:?}");
        }
        let fall = [start[2] - now[2], start[3] - now[3]];
        assert!(fall[0] > 0.0 && fall[1] > 2.0 * fall[0], "{fall:?}");
        assert!(now[4] <= 1.0 + 1e-12, "{now:?}");
    }

    #[test]
    fn bad_interfaces_are_refused_by_name() {
        let cases: [(&[&str], &str); 6] = [
            (
                &["--output", "nothing"],
                "no probe column of that name; it has: solid_x",
            ),
            (&["--input", "grid.nr"], "not an input"),
            (
                &["--input", "boundaries.x_min.speed"],
                "x_min is not a moving wall",
            ),
            (
                &["--parameter", "solid.law.parameters.K"],
                "no setting solid.law.parameters.K",
            ),
            (
                &["--range", "nothing=0..1"],
                "no parameter or input `nothing`",
            ),
            (&["--wrong", "x"], "unknown flag `--wrong`"),
        ];
        for (a, needle) in cases {
            let e = Spec::from_args(&sphere(), &args(a)).unwrap_err();
            assert!(e.contains(needle), "{a:?}: {e}");
        }
    }

    /// `--range` against the scene: a start value outside, a bound that is not a number, MIN
    /// above MAX, an Integer's bounds outside FMI 2's 32 bits are refused by name; `inf` is no
    /// bound (never written as a number); a bound the scene refuses (an open one) is declared
    /// as the nearest value it accepts.
    #[test]
    fn ranges_are_checked_against_the_scene() {
        let with = |extra: &[&str]| {
            let mut a: Vec<&str> = vec!["--parameter", "solid.law.parameters.G=Pa"];
            a.extend_from_slice(extra);
            Spec::from_args(&sphere(), &args(&a))
        };
        let refused: [(&[&str], &str); 6] = [
            (
                &["--range", "solid.law.parameters.G=5..1"],
                "MIN 5 is above MAX 1",
            ),
            (
                &["--range", "solid.law.parameters.G=1e7..1e8"],
                "the start value 180000 (the scene's) is outside the range",
            ),
            (
                &["--range", "solid.law.parameters.G=nan..1"],
                "`nan` is not a number",
            ),
            (
                &["--range", "solid.law.parameters.G=inf..1e10"],
                "MIN cannot be inf",
            ),
            (
                &[
                    "--parameter",
                    "grid.nr",
                    "--range",
                    "grid.nr=1..9223372036854775807",
                ],
                "`grid.nr` is an Integer: its bounds must be whole numbers in [-2147483648, 2147483647]",
            ),
            (
                &["--parameter", "grid.nr", "--range", "grid.nr=1.5..100"],
                "got 1.5",
            ),
        ];
        for (a, needle) in refused {
            let e = with(a).unwrap_err();
            assert!(e.contains(needle), "{a:?}: {e}");
        }
        // No upper bound: none declared.
        let spec = with(&["--range", "solid.law.parameters.G=1..inf"]).unwrap();
        let vars = spec.variables().unwrap();
        let g = vars
            .iter()
            .find(|v| v.name == "solid.law.parameters.G")
            .unwrap();
        assert_eq!((g.min, g.max), (Some(1.0), None));
        let xml = crate::description::fmi2(&spec, &vars);
        assert!(!xml.contains("inf") && !xml.contains("NaN"), "{xml}");
        // Open bounds: G > 0 (the law's range), a radius > 0, time.cfl > 0 are declared as the
        // smallest double above 0, which the scene and the law accept.
        let spec = Spec::from_args(&sphere(), &args(SPHERE)).unwrap();
        let vars = spec.variables().unwrap();
        let smallest = f64::from_bits(1);
        for name in ["solid.law.parameters.G", "solid.shape.radius", "time.cfl"] {
            let v = vars.iter().find(|v| v.name == name).unwrap();
            assert_eq!(v.min, Some(smallest), "{name}");
            assert!(v.check_range(0.0).is_err(), "{name}");
        }
        // A closed bound the scene accepts stays as given.
        let nr = vars.iter().find(|v| v.name == "grid.nr").unwrap();
        assert_eq!((nr.min, nr.max), (Some(2.0), Some(1000.0)));
    }
}
