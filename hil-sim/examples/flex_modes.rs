//! The flexible plant's modes across the workspace (motors held), as the
//! markdown table of docs/vibration.md:
//! `cargo run -p triquint-sim --example flex_modes`.

use nalgebra::Vector3;
use triquint_shared::Robot;
use triquint_shared::kinematics::Pose;
use triquint_sim::flex::{FlexParams, FlexPlant};
use triquint_sim::plant::PlantConfig;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let robot = Robot::default();
    let params = FlexParams::default();
    let m = robot.model::<f64>();
    let q0 = Pose::from_cartesian(&m, Vector3::from(params.reference_pose))?.q;
    let plant = FlexPlant::new(&robot, PlantConfig::default(), params, q0)?;
    println!("| platform (mm) | modes (Hz, damping ratio; * platform share > 0.5) |");
    println!("|---|---|");
    let poses = [
        [0.0, 0.0, 600.0],
        [0.0, 0.0, 500.0],
        [0.0, 0.0, 700.0],
        [120.0, 0.0, 600.0],
        [-120.0, 0.0, 600.0],
        [0.0, 120.0, 600.0],
        [-86.0, 83.66, 597.66],
        [86.0, -83.66, 602.34],
        [0.0, 84.85, 684.85],
        [0.0, -84.85, 515.15],
    ];
    for p in poses {
        let r = Vector3::from(p) * 1e-3;
        let modes = plant.modes(r)?;
        let cells: Vec<String> = modes
            .iter()
            .map(|m| {
                format!(
                    "{:.1}{} ({:.3})",
                    m.hz,
                    if m.platform_share > 0.5 { "*" } else { "" },
                    m.damping
                )
            })
            .collect();
        println!(
            "| ({:.0}, {:.0}, {:.0}) | {} |",
            p[0],
            p[1],
            p[2],
            cells.join(", ")
        );
    }
    Ok(())
}
