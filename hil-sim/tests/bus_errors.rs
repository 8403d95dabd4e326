//! The CAN error counters of HeartbeatExt are fed. On the
//! simulated bus, the fault layer's confinement rules (ISO 11898-1) move
//! them; the drives report them to the host.

use triquint_shared::Robot;
use triquint_shared::kinematics::Pose;
use triquint_shared::protocol::{Msg, decode};
use triquint_sim::{Fault, FaultWindow, Sim, SimConfig};

/// The highest (TEC, REC) each node reported in a HeartbeatExt that
/// reached the host, over `secs` s.
fn reported(windows: Vec<FaultWindow>, secs: u64) -> [(u8, u8); 3] {
    let m = Robot::default().model::<f64>();
    let q0 = Pose::from_cartesian(&m, nalgebra::Vector3::new(0.0, 0.0, 0.62))
        .unwrap()
        .q;
    let mut sim = Sim::with_faults(&Robot::default(), q0, SimConfig::default(), windows, 3);
    let mut last = [(0, 0); 3];
    for k in 1..=secs * 10 {
        sim.run_until(k * 100_000_000).unwrap();
        while let Some(d) = sim.host_receive() {
            if let Ok((Msg::HeartbeatExt(h), n @ 1..=3)) = decode(&d.frame) {
                let l = &mut last[n as usize - 1];
                *l = (l.0.max(h.tx_errors), l.1.max(h.rx_errors));
            }
        }
    }
    last
}

#[test]
fn a_clean_bus_reports_zero_errors() {
    assert_eq!(reported(vec![], 2), [(0, 0); 3]);
}

#[test]
fn lost_frames_raise_the_senders_tec_and_the_receivers_rec() {
    // Node 1's frames lost at every receiver half of the time: its TEC climbs
    // (+8 per frame some receiver lost, −1 per clean one).
    let loss = |id| FaultWindow::new(Fault::Loss { rate: 0.5 }, 0, u64::MAX).on_ids(id..=id);
    let r = reported(vec![loss(0x701), loss(0x741)], 3);
    assert!(r[0].0 >= 64, "node 1 TEC {r:?}");
    assert_eq!((r[1].0, r[2].0), (0, 0), "{r:?}");
    // Every frame lost at every receiver for 1 s: each node's TEC (+8 per
    // frame) and REC (+1 per frame of the others) rise; the host sees the
    // heartbeats that report them once the window has passed.
    let w = FaultWindow::new(Fault::Loss { rate: 1.0 }, 0, 1_000_000_000);
    let r = reported(vec![w], 2);
    for (tec, rec) in r {
        assert!(tec >= 128, "error-passive TEC {r:?}");
        assert!(rec >= 10, "REC {r:?}");
    }
}
