//! The `modelDescription.xml` of both FMUs, generated from the one variable table
//! ([`crate::model::VARIABLES`]) so the XML and the code cannot drift apart; the GUID /
//! instantiation token is a hash of that table and the crate version, and instantiation refuses
//! another one.

use crate::model::{Causality, Kind, VARIABLES, Variable};
use std::fmt::Write;

/// The model identifier: the library is `binaries/<platform>/sphere_impact.so`.
pub const MODEL_IDENTIFIER: &str = "sphere_impact";

const DESCRIPTION: &str = "Axisymmetric impact of a hyperelastic sphere on a no-slip substrate in a viscous fluid (Esmailzadeh & Passandideh-Fard 2014, section 5.1), solved by efsi (full-Eulerian FSI). Contact force and energies are whole-body values: 2 pi times efsi's per-radian probes.";

const UNITS: &[(&str, &str)] = &[
    ("m", r#"m="1""#),
    ("s", r#"s="1""#),
    ("m/s", r#"m="1" s="-1""#),
    ("m/s2", r#"m="1" s="-2""#),
    ("kg/m3", r#"kg="1" m="-3""#),
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
            "|{} {} {:?} {:?} {:?} {:?}",
            v.vr, v.name, v.kind, v.causality, v.unit, v.start
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

fn header(out: &mut String, version: &str, token_attribute: &str) {
    let _ = write!(
        out,
        r#"<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription
  fmiVersion="{version}"
  modelName="sphere_impact"
  {token_attribute}="{token}"
  description="{description}"
  generationTool="efsi-fmu {crate_version}"
  version="{crate_version}"
  variableNamingConvention="flat""#,
        token = token(),
        description = escape(DESCRIPTION),
        crate_version = env!("CARGO_PKG_VERSION"),
    );
}

fn units_categories_experiment(out: &mut String) {
    out.push_str("  <UnitDefinitions>\n");
    for (name, base) in UNITS {
        let _ = writeln!(out, r#"    <Unit name="{name}"><BaseUnit {base}/></Unit>"#);
    }
    out.push_str(
        r#"  </UnitDefinitions>
  <LogCategories>
    <Category name="logStatusError" description="Errors: refused parameters, failed steps, unsupported calls"/>
    <Category name="logInfo" description="The grid and stages at initialisation, solver steps per communication step (debug logging)"/>
  </LogCategories>
  <DefaultExperiment startTime="0" stopTime="0.07" stepSize="0.001"/>
"#,
    );
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
        let _ = writeln!(
            out,
            r#"    <!-- index {index} -->
    <ScalarVariable name="{name}" valueReference="{vr}" causality="{causality}" variability="{variability}"{initial}
      description="{description}">
      <{element}{start}{unit}/>
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
        let _ = writeln!(out, r#"      <Unknown index="{k}"/>"#);
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
                    r#"    <{element} {attributes}{start}{unit}
      description="{description}"/>"#
                );
            }
        }
    }
    out.push_str("  </ModelVariables>\n  <ModelStructure>\n");
    for vr in &outputs {
        let _ = writeln!(out, r#"    <Output valueReference="{vr}"/>"#);
    }
    for vr in &outputs {
        let _ = writeln!(out, r#"    <InitialUnknown valueReference="{vr}"/>"#);
    }
    out.push_str("  </ModelStructure>\n</fmiModelDescription>\n");
    out
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
        }
    }
}
