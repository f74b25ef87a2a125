//! What `cargo xtask fmu` packages besides the library and the scene: the `modelDescription.xml`
//! of both FMUs, `documentation/index.html` and the licence, all generated from the FMU's spec
//! ([`crate::spec::Spec::variables`]) so the XML, the documentation and the code cannot drift
//! apart. The GUID / instantiation token is a hash of the spec and the crate version
//! ([`Spec::token`]), and instantiation refuses another one.
//!
//! The model structure declares that no output depends directly on the input at the same
//! communication point (`dependencies=""`: the base acceleration acts through the next
//! `doStep`), so an importer connecting an output back to the input builds no algebraic loop;
//! the outputs' initial values depend on the parameters (no `dependencies` attribute: all
//! knowns). Ranged parameters and the input carry `min`/`max`.

use crate::log::CATEGORIES;
use crate::spec::{Causality, Kind, Spec, Variable};
use efsi_run::SceneOutput;
use std::fmt::Write;

fn model_description(spec: &Spec) -> String {
    format!(
        "The efsi scene `{}` (full-Eulerian fluid-structure interaction), run by efsi's solver; the outputs are the scene's probes as efsi run writes them to probes.csv (per radian in axisymmetric scenes).",
        spec.name
    )
}

/// The licence the FMU is distributed under (the workspace's).
pub const LICENSE: &str = env!("CARGO_PKG_LICENSE");

/// Base units of the units a variable may name (others are declared without base units).
const UNITS: &[(&str, &str)] = &[
    ("m", r#"m="1""#),
    ("s", r#"s="1""#),
    ("m/s", r#"m="1" s="-1""#),
    ("m/s2", r#"m="1" s="-2""#),
    ("kg/m3", r#"kg="1" m="-3""#),
    ("Pa", r#"kg="1" m="-1" s="-2""#),
    ("Pa.s", r#"kg="1" m="-1" s="-1""#),
    ("N", r#"kg="1" m="1" s="-2""#),
    ("J", r#"kg="1" m="2" s="-2""#),
    ("N/m", r#"kg="1" s="-2""#),
    ("J/m", r#"kg="1" m="1" s="-2""#),
    // Per radian: the probes of axisymmetric scenes (×2π for the whole body or domain).
    ("N/rad", r#"kg="1" m="1" s="-2" rad="-1""#),
    ("J/rad", r#"kg="1" m="2" s="-2" rad="-1""#),
    ("m3/rad", r#"m="3" rad="-1""#),
];

/// `s` with the XML special characters escaped.
fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn causality(v: &Variable) -> &'static str {
    match v.causality {
        Causality::Independent => "independent",
        Causality::Parameter => "parameter",
        Causality::Input => "input",
        Causality::Output => "output",
    }
}

fn variability(v: &Variable) -> &'static str {
    match (v.causality, v.kind) {
        (Causality::Parameter, _) => "fixed",
        (_, Kind::Real) => "continuous",
        _ => "discrete",
    }
}

/// `Y-m-dTH:M:SZ` of `seconds` since the Unix epoch (UTC).
fn date_time(seconds: u64) -> String {
    let (days, rest) = ((seconds / 86_400) as i64, seconds % 86_400);
    // Days to a civil date (Howard Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}Z",
        rest / 3600,
        rest / 60 % 60,
        rest % 60
    )
}

/// When the description is generated: `$SOURCE_DATE_EPOCH` (reproducible builds) or now.
fn generated_at() -> String {
    let seconds = std::env::var("SOURCE_DATE_EPOCH")
        .ok()
        .and_then(|s| s.trim().parse().ok())
        .unwrap_or_else(|| {
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_secs())
        });
    date_time(seconds)
}

fn header(out: &mut String, spec: &Spec, version: &str, token_attribute: &str) {
    let _ = write!(
        out,
        r#"<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription
  fmiVersion="{version}"
  modelName="{name}"
  {token_attribute}="{token}"
  description="{description}"
  author="the efsi developers"
  copyright="Copyright the efsi developers"
  license="{LICENSE} (documentation/licenses/license.txt)"
  generationTool="efsi-fmu {crate_version}"
  generationDateAndTime="{date}"
  version="{crate_version}"
  variableNamingConvention="flat""#,
        name = escape(&spec.name),
        token = spec.token(),
        description = escape(&model_description(spec)),
        crate_version = env!("CARGO_PKG_VERSION"),
        date = generated_at(),
    );
}

fn units_categories_experiment(out: &mut String, vars: &[Variable], step: f64, stop: f64) {
    let mut units: Vec<&str> = vars.iter().filter_map(|v| v.unit.as_deref()).collect();
    units.sort_unstable();
    units.dedup();
    out.push_str("  <UnitDefinitions>\n");
    for name in units {
        match UNITS.iter().find(|(u, _)| *u == name) {
            Some((_, base)) => {
                let _ = writeln!(
                    out,
                    r#"    <Unit name="{}"><BaseUnit {base}/></Unit>"#,
                    escape(name)
                );
            }
            None => {
                let _ = writeln!(out, r#"    <Unit name="{}"/>"#, escape(name));
            }
        }
    }
    out.push_str("  </UnitDefinitions>\n  <LogCategories>\n");
    for (name, what) in CATEGORIES {
        let _ = writeln!(
            out,
            r#"    <Category name="{name}" description="{}"/>"#,
            escape(what)
        );
    }
    let _ = writeln!(
        out,
        r#"  </LogCategories>
  <DefaultExperiment startTime="0" stopTime="{stop:?}" stepSize="{step:?}"/>"#
    );
}

/// The default experiment: the scene's end, in steps of its probe interval (or a hundredth of
/// the end).
fn experiment(spec: &Spec) -> (f64, f64) {
    match spec.parsed_scene() {
        Ok(s) => (
            s.output_spec()
                .ok()
                .and_then(|o| o.probe_every)
                .unwrap_or(s.time.end / 100.0),
            s.time.end,
        ),
        Err(_) => (1.0, 100.0),
    }
}

/// ` min="…" max="…"` for a ranged variable.
fn range(v: &Variable) -> String {
    let number = |x: f64| match v.kind {
        Kind::Real => format!("{x:?}"),
        _ => format!("{}", x as i64),
    };
    let mut s = String::new();
    if let Some(m) = v.min {
        let _ = write!(s, r#" min="{}""#, number(m));
    }
    if let Some(m) = v.max {
        let _ = write!(s, r#" max="{}""#, number(m));
    }
    s
}

/// `modelDescription.xml` of the FMI 2.0 Co-Simulation FMU of `spec` (variables `vars`).
pub fn fmi2(spec: &Spec, vars: &[Variable]) -> String {
    let mut out = String::new();
    header(&mut out, spec, "2.0", "guid");
    out.push_str("\n  numberOfEventIndicators=\"0\">\n");
    let _ = writeln!(
        out,
        r#"  <CoSimulation
    modelIdentifier="{identifier}"
    canHandleVariableCommunicationStepSize="true"
    canInterpolateInputs="false"
    maxOutputDerivativeOrder="0"
    canRunAsynchronuously="false"
    canBeInstantiatedOnlyOncePerProcess="false"
    canNotUseMemoryManagementFunctions="true"
    canGetAndSetFMUstate="true"
    canSerializeFMUstate="true"
    providesDirectionalDerivative="false"/>"#,
        identifier = spec.identifier()
    );
    let (step, stop) = experiment(spec);
    units_categories_experiment(&mut out, vars, step, stop);
    out.push_str("  <ModelVariables>\n");
    let mut outputs = Vec::new();
    for (k, v) in vars.iter().enumerate() {
        let initial = match v.causality {
            Causality::Parameter => r#" initial="exact""#,
            Causality::Output => r#" initial="calculated""#,
            _ => "",
        };
        if v.causality == Causality::Output {
            outputs.push(k + 1);
        }
        let element = match v.kind {
            Kind::Real => "Real",
            Kind::Int32 | Kind::Int64 => "Integer",
            Kind::String => "String",
        };
        let start = v
            .start
            .as_deref()
            .map_or(String::new(), |s| format!(r#" start="{}""#, escape(s)));
        let unit = v
            .unit
            .as_deref()
            .map_or(String::new(), |u| format!(r#" unit="{}""#, escape(u)));
        let range = match v.kind {
            Kind::Real | Kind::Int32 => range(v),
            _ => String::new(),
        };
        let _ = writeln!(
            out,
            r#"    <!-- index {index} -->
    <ScalarVariable name="{name}" valueReference="{vr}" causality="{causality}" variability="{variability}"{initial}
      description="{description}">
      <{element}{start}{unit}{range}/>
    </ScalarVariable>"#,
            index = k + 1,
            name = escape(&v.name),
            vr = v.vr,
            causality = causality(v),
            variability = variability(v),
            description = escape(&v.description),
        );
    }
    out.push_str("  </ModelVariables>\n  <ModelStructure>\n    <Outputs>\n");
    for k in &outputs {
        let _ = writeln!(out, r#"      <Unknown index="{k}" dependencies=""/>"#);
    }
    out.push_str("    </Outputs>\n    <InitialUnknowns>\n");
    for k in &outputs {
        let _ = writeln!(out, r#"      <Unknown index="{k}"/>"#);
    }
    out.push_str("    </InitialUnknowns>\n  </ModelStructure>\n</fmiModelDescription>\n");
    out
}

/// `modelDescription.xml` of the FMI 3.0 Co-Simulation FMU of `spec` (variables `vars`).
pub fn fmi3(spec: &Spec, vars: &[Variable]) -> String {
    let mut out = String::new();
    header(&mut out, spec, "3.0", "instantiationToken");
    out.push_str(">\n");
    let _ = writeln!(
        out,
        r#"  <CoSimulation
    modelIdentifier="{identifier}"
    canHandleVariableCommunicationStepSize="true"
    canGetAndSetFMUState="true"
    canSerializeFMUState="true"
    providesDirectionalDerivatives="false"
    providesAdjointDerivatives="false"
    canBeInstantiatedOnlyOncePerProcess="false"
    maxOutputDerivativeOrder="0"
    hasEventMode="false"
    providesIntermediateUpdate="false"
    canReturnEarlyAfterIntermediateUpdate="false"/>"#,
        identifier = spec.identifier()
    );
    let (step, stop) = experiment(spec);
    units_categories_experiment(&mut out, vars, step, stop);
    out.push_str("  <ModelVariables>\n");
    let mut outputs = Vec::new();
    for v in vars {
        if v.causality == Causality::Output {
            outputs.push(v.vr);
        }
        fmi3_variable(&mut out, v);
    }
    out.push_str("  </ModelVariables>\n  <ModelStructure>\n");
    for vr in &outputs {
        let _ = writeln!(
            out,
            r#"    <Output valueReference="{vr}" dependencies=""/>"#
        );
    }
    for vr in &outputs {
        let _ = writeln!(out, r#"    <InitialUnknown valueReference="{vr}"/>"#);
    }
    out.push_str("  </ModelStructure>\n</fmiModelDescription>\n");
    out
}

/// One FMI 3.0 variable element of `v` (a `<Start>` child for a string's start).
fn fmi3_variable(out: &mut String, v: &Variable) {
    let element = match v.kind {
        Kind::Real => "Float64",
        Kind::Int32 => "Int32",
        Kind::Int64 => "Int64",
        Kind::String => "String",
    };
    let initial = if v.causality == Causality::Output {
        r#" initial="calculated""#
    } else {
        ""
    };
    let unit = v
        .unit
        .as_deref()
        .map_or(String::new(), |u| format!(r#" unit="{}""#, escape(u)));
    let attributes = format!(
        r#"name="{name}" valueReference="{vr}" causality="{causality}" variability="{variability}"{initial}"#,
        name = escape(&v.name),
        vr = v.vr,
        causality = causality(v),
        variability = variability(v),
    );
    let description = escape(&v.description);
    match (v.kind, v.start.as_deref()) {
        (Kind::String, Some(s)) => {
            let _ = writeln!(
                out,
                r#"    <String {attributes}
      description="{description}">
      <Start value="{}"/>
    </String>"#,
                escape(s)
            );
        }
        (_, start) => {
            let start = start.map_or(String::new(), |s| format!(r#" start="{s}""#));
            let _ = writeln!(
                out,
                r#"    <{element} {attributes}{start}{unit}{range}
      description="{description}"/>"#,
                range = range(v),
            );
        }
    }
}

/// `documentation/index.html`: what the model is, its variables (from the table) and how it
/// steps and refuses.
pub fn documentation(spec: &Spec, vars: &[Variable]) -> String {
    let mut rows = String::new();
    for v in vars {
        let range = match (v.min, v.max) {
            (None, None) => String::new(),
            (a, b) => format!(
                "[{}, {}]",
                a.map_or("−∞".into(), crate::spec::short),
                b.map_or("∞".into(), crate::spec::short)
            ),
        };
        let _ = writeln!(
            rows,
            "<tr><td><code>{}</code></td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            escape(&v.name),
            causality(v),
            escape(v.unit.as_deref().unwrap_or("")),
            escape(v.start.as_deref().unwrap_or("")),
            range,
            escape(&v.description)
        );
    }
    format!(
        r#"<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{name}</title></head>
<body>
<h1>{name} (efsi {version})</h1>
<p>{description}</p>
<p>Generated by efsi-fmu {version}. Licence: {LICENSE} (<a href="licenses/license.txt">licenses/license.txt</a>).</p>
<h2>Variables</h2>
<table border="1">
<tr><th>name</th><th>causality</th><th>unit</th><th>start</th><th>range</th><th>description</th></tr>
{rows}</table>
<h2>Stepping</h2>
<p>Each doStep takes as many solver steps as it needs (CFL-limited, at most
<code>max_solver_steps_per_step</code>) and lands exactly on the next communication point, for any
step size. A step that would need more solver steps, or whose solver fails, is refused with
<code>Discard</code> and the instance exactly at the start of the step (FMI 3.0: it stays in step
mode; FMI 2.0: it is in <i>stepFailed</i>, set an FMU state to go on). Illegal calls and
arguments return <code>Error</code>; the instance is then in the Error state until an FMU state
is set or it is reset. Values outside a variable's range are refused.</p>
<h2>FMU states</h2>
<p>FMU states can be got, set (in any mode) and serialised; serialised states carry no path of
the extraction folder and set into any instance of this build.</p>
<h2>Scene</h2>
<p>The scene is <code>resources/scene.ron</code>; each parameter is one of its settings by its path
(the syntax of <code>efsi run --set</code>), applied when initialisation ends. A solid's law is
a library in this FMU's <code>binaries/</code> folder, chosen by name; nothing outside the FMU is
searched.</p>
</body></html>
"#,
        version = env!("CARGO_PKG_VERSION"),
        name = escape(&spec.name),
        description = escape(&model_description(spec)),
    )
}

/// `documentation/licenses/license.txt`.
pub fn license() -> String {
    format!(
        r#"efsi scene FMU (efsi {version}) — licence: {LICENSE}

The FMU's library, the law libraries in binaries/ and this documentation are part of efsi and
are dual-licensed under the MIT licence or the Apache License, Version 2.0
(https://www.apache.org/licenses/LICENSE-2.0), at your option. The Rust crates compiled into
the libraries are under the MIT and/or Apache-2.0 licences of their authors.

MIT License

Copyright the efsi developers

Permission is hereby granted, free of charge, to any person obtaining a copy of this software
and associated documentation files (the "Software"), to deal in the Software without
restriction, including without limitation the rights to use, copy, modify, merge, publish,
distribute, sublicense, and/or sell copies of the Software, and to permit persons to whom the
Software is furnished to do so, subject to the following conditions:

The above copyright notice and this permission notice shall be included in all copies or
substantial portions of the Software.

THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND, EXPRESS OR IMPLIED, INCLUDING
BUT NOT LIMITED TO THE WARRANTIES OF MERCHANTABILITY, FITNESS FOR A PARTICULAR PURPOSE AND
NONINFRINGEMENT. IN NO EVENT SHALL THE AUTHORS OR COPYRIGHT HOLDERS BE LIABLE FOR ANY CLAIM,
DAMAGES OR OTHER LIABILITY, WHETHER IN AN ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING FROM,
OUT OF OR IN CONNECTION WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN THE SOFTWARE.
"#,
        version = env!("CARGO_PKG_VERSION"),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates_are_civil_utc() {
        assert_eq!(date_time(0), "1970-01-01T00:00:00Z");
        assert_eq!(date_time(951_782_400), "2000-02-29T00:00:00Z");
        assert_eq!(date_time(1_700_000_000), "2023-11-14T22:13:20Z");
    }
}
