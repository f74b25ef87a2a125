//! What `cargo xtask fmu` packages besides the library: the `modelDescription.xml` of both FMUs,
//! `documentation/index.html` and the licence, all generated from the one variable table
//! ([`crate::params::VARIABLES`]) so the XML, the documentation and the code cannot drift
//! apart. The GUID / instantiation token is a hash of that table and the crate version, and
//! instantiation refuses another one.
//!
//! The model structure declares that no output depends directly on the input at the same
//! communication point (`dependencies=""`: the base acceleration acts through the next
//! `doStep`), so an importer connecting an output back to the input builds no algebraic loop;
//! the outputs' initial values depend on the parameters (no `dependencies` attribute: all
//! knowns). Ranged parameters and the input carry `min`/`max`.

use crate::log::CATEGORIES;
use crate::params::{Causality, Kind, VARIABLES, Variable};
use std::fmt::Write;

/// The model identifier: the library is `binaries/<platform>/sphere_impact.so`.
pub const MODEL_IDENTIFIER: &str = "sphere_impact";

const DESCRIPTION: &str = "Axisymmetric impact of a hyperelastic sphere on a no-slip substrate in a viscous fluid (Esmailzadeh & Passandideh-Fard 2014, section 5.1), solved by efsi (full-Eulerian FSI). Contact force and energies are whole-body values: 2 pi times efsi's per-radian probes.";

/// The licence the FMU is distributed under (the workspace's).
pub const LICENSE: &str = env!("CARGO_PKG_LICENSE");

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
];

fn fnv(seed: u64, text: &str) -> u64 {
    let mut h = seed;
    for b in text.bytes() {
        h = (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// The FMI 2.0 GUID and FMI 3.0 instantiation token: `{xxxxxxxx-xxxx-xxxx-xxxx-xxxxxxxxxxxx}`
/// from a hash of the variable table and the crate version.
pub fn token() -> String {
    let mut text = format!("sphere_impact {}", env!("CARGO_PKG_VERSION"));
    for v in VARIABLES {
        let _ = write!(
            text,
            "|{} {} {:?} {:?} {:?} {:?} {:?} {:?}",
            v.vr, v.name, v.kind, v.causality, v.unit, v.start, v.min, v.max
        );
    }
    let a = fnv(0xcbf2_9ce4_8422_2325, &text);
    let b = fnv(a ^ 0x9e37_79b9_7f4a_7c15, &text);
    format!(
        "{{{:08x}-{:04x}-{:04x}-{:04x}-{:012x}}}",
        a >> 32,
        (a >> 16) & 0xffff,
        a & 0xffff,
        b >> 48,
        b & 0xffff_ffff_ffff
    )
}

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

fn header(out: &mut String, version: &str, token_attribute: &str) {
    let _ = write!(
        out,
        r#"<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription
  fmiVersion="{version}"
  modelName="sphere_impact"
  {token_attribute}="{token}"
  description="{description}"
  author="the efsi developers"
  copyright="Copyright the efsi developers"
  license="{LICENSE} (documentation/licenses/license.txt)"
  generationTool="efsi-fmu {crate_version}"
  generationDateAndTime="{date}"
  version="{crate_version}"
  variableNamingConvention="flat""#,
        token = token(),
        description = escape(DESCRIPTION),
        crate_version = env!("CARGO_PKG_VERSION"),
        date = generated_at(),
    );
}

fn units_categories_experiment(out: &mut String) {
    out.push_str("  <UnitDefinitions>\n");
    for (name, base) in UNITS {
        let _ = writeln!(out, r#"    <Unit name="{name}"><BaseUnit {base}/></Unit>"#);
    }
    out.push_str("  </UnitDefinitions>\n  <LogCategories>\n");
    for (name, what) in CATEGORIES {
        let _ = writeln!(
            out,
            r#"    <Category name="{name}" description="{}"/>"#,
            escape(what)
        );
    }
    out.push_str(
        r#"  </LogCategories>
  <DefaultExperiment startTime="0" stopTime="0.07" stepSize="0.001"/>
"#,
    );
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

/// `modelDescription.xml` of the FMI 2.0 Co-Simulation FMU.
pub fn fmi2() -> String {
    let mut out = String::new();
    header(&mut out, "2.0", "guid");
    out.push_str("\n  numberOfEventIndicators=\"0\">\n");
    let _ = writeln!(
        out,
        r#"  <CoSimulation
    modelIdentifier="{MODEL_IDENTIFIER}"
    canHandleVariableCommunicationStepSize="true"
    canInterpolateInputs="false"
    maxOutputDerivativeOrder="0"
    canRunAsynchronuously="false"
    canBeInstantiatedOnlyOncePerProcess="false"
    canNotUseMemoryManagementFunctions="true"
    canGetAndSetFMUstate="true"
    canSerializeFMUstate="true"
    providesDirectionalDerivative="false"/>"#
    );
    units_categories_experiment(&mut out);
    out.push_str("  <ModelVariables>\n");
    let mut outputs = Vec::new();
    for (k, v) in VARIABLES.iter().enumerate() {
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
            .map_or(String::new(), |s| format!(r#" start="{}""#, escape(s)));
        let unit = v.unit.map_or(String::new(), |u| format!(r#" unit="{u}""#));
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
            name = v.name,
            vr = v.vr,
            causality = causality(v),
            variability = variability(v),
            description = escape(v.description),
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

/// `modelDescription.xml` of the FMI 3.0 Co-Simulation FMU.
pub fn fmi3() -> String {
    let mut out = String::new();
    header(&mut out, "3.0", "instantiationToken");
    out.push_str(">\n");
    let _ = writeln!(
        out,
        r#"  <CoSimulation
    modelIdentifier="{MODEL_IDENTIFIER}"
    canHandleVariableCommunicationStepSize="true"
    canGetAndSetFMUState="true"
    canSerializeFMUState="true"
    providesDirectionalDerivatives="false"
    providesAdjointDerivatives="false"
    canBeInstantiatedOnlyOncePerProcess="false"
    maxOutputDerivativeOrder="0"
    hasEventMode="false"
    providesIntermediateUpdate="false"
    canReturnEarlyAfterIntermediateUpdate="false"/>"#
    );
    units_categories_experiment(&mut out);
    out.push_str("  <ModelVariables>\n");
    let mut outputs = Vec::new();
    for v in VARIABLES {
        if v.causality == Causality::Output {
            outputs.push(v.vr);
        }
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
        let unit = v.unit.map_or(String::new(), |u| format!(r#" unit="{u}""#));
        let attributes = format!(
            r#"name="{name}" valueReference="{vr}" causality="{causality}" variability="{variability}"{initial}"#,
            name = v.name,
            vr = v.vr,
            causality = causality(v),
            variability = variability(v),
        );
        let description = escape(v.description);
        match (v.kind, v.start) {
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

/// `documentation/index.html`: what the model is, its variables (from the table) and how it
/// steps and refuses.
pub fn documentation() -> String {
    let mut rows = String::new();
    for v in VARIABLES {
        let range = match (v.min, v.max) {
            (None, None) => String::new(),
            (a, b) => format!(
                "[{}, {}]",
                a.map_or("−∞".into(), |x| format!("{x}")),
                b.map_or("∞".into(), |x| format!("{x}"))
            ),
        };
        let _ = writeln!(
            rows,
            "<tr><td><code>{}</code></td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            v.name,
            causality(v),
            v.unit.unwrap_or(""),
            escape(v.start.unwrap_or("")),
            range,
            escape(v.description)
        );
    }
    format!(
        r#"<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>sphere_impact</title></head>
<body>
<h1>sphere_impact {version}</h1>
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
<h2>Laws</h2>
<p>The hyperelastic laws are the libraries in this FMU's <code>binaries/</code> folder, chosen by
name with the <code>law</code> parameter; nothing outside the FMU is searched.</p>
</body></html>
"#,
        version = env!("CARGO_PKG_VERSION"),
        description = escape(DESCRIPTION),
    )
}

/// `documentation/licenses/license.txt`.
pub fn license() -> String {
    format!(
        r#"sphere_impact FMU (efsi {version}) — licence: {LICENSE}

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
    fn token_is_a_guid() {
        let t = token();
        assert_eq!(t.len(), 38, "{t}");
        assert!(t.starts_with('{') && t.ends_with('}'));
        assert_eq!(t.matches('-').count(), 4);
    }

    #[test]
    fn descriptions_list_every_variable_once() {
        for xml in [fmi2(), fmi3()] {
            for v in VARIABLES {
                assert_eq!(
                    xml.matches(&format!("name=\"{}\"", v.name)).count(),
                    1,
                    "{}",
                    v.name
                );
            }
            assert!(xml.contains(&token()));
            // Outputs do not feed through from the input.
            assert_eq!(xml.matches(r#"dependencies="""#).count(), 8);
            assert!(xml.contains(r#"min="-1000.0" max="1000.0""#));
        }
        assert!(documentation().contains("max_solver_steps_per_step"));
    }

    #[test]
    fn dates_are_civil_utc() {
        assert_eq!(date_time(0), "1970-01-01T00:00:00Z");
        assert_eq!(date_time(951_782_400), "2000-02-29T00:00:00Z");
        assert_eq!(date_time(1_700_000_000), "2023-11-14T22:13:20Z");
    }
}
