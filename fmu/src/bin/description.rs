//! `efsi-fmu-description 2|3|scene|doc|license`: print the FMI 2.0 or FMI 3.0
//! `modelDescription.xml`, the scene of the default parameters, `documentation/index.html` or
//! the licence (what `cargo xtask fmu` packages).

use std::process::ExitCode;

fn main() -> ExitCode {
    let arg = std::env::args().nth(1).unwrap_or_default();
    let text = match arg.as_str() {
        "2" => sphere_impact::description::fmi2(),
        "3" => sphere_impact::description::fmi3(),
        "scene" => sphere_impact::Params::default().scene_ron("neo_hookean", 0.07, 0.001),
        "doc" => sphere_impact::description::documentation(),
        "license" => sphere_impact::description::license(),
        _ => {
            eprintln!("usage: efsi-fmu-description 2|3|scene|doc|license");
            return ExitCode::FAILURE;
        }
    };
    print!("{text}");
    ExitCode::SUCCESS
}
