//! Measuring the machine's resonances as Klipper's TEST_RESONANCES does: each
//! axis in turn swept by a chirp within the machine's ceilings, through the
//! firmware's control law on the flexible plant; the encoders and the
//! platform's accelerometer recorded; the frequency response from the
//! slider's motion (encoder) to the platform's acceleration (accelerometer)
//! estimated as the ratio of the two records' Fourier transforms (exact for
//! a linear system whose records start and end at rest, whatever the sweep
//! rate); and each peak fitted with a damped second-order mode.

use nalgebra::{Complex, DMatrix, DVector, Vector3};
use serde::Serialize;
use triquint_shared::Limits;
use triquint_shared::dynamics;
use triquint_shared::kinematics::{KinematicsError, Pose};
use triquint_shared::machine::Machine;
use triquint_shared::protocol::DriveConfig;
use triquint_shared::quintic::JointMotion;

use crate::flex::{FlexError, FlexParams, FlexPlant};
use crate::plant::PlantConfig;
use crate::plant_model::PlantModel;
use crate::test_reference;

/// One count of an ADXL345 at full resolution (3.9 mg, m/s²): the
/// accelerometer is read as Klipper's reads it.
pub const ACCEL_COUNT_M_S2: f64 = 3.9e-3 * 9.80665;
/// The share of each ceiling the sweep may use.
const CEILING_SHARE: f64 = 0.9;
/// Holding still before the sweep, and after it for the ringing to die (s).
const HOLD_S: f64 = 1.0;
const TAIL_S: f64 = 1.5;
/// Fade in and out of the chirp (s), so that it starts and ends at rest.
const FADE_S: f64 = 0.5;
/// Frequency grid of the response (Hz).
const GRID_HZ: f64 = 0.05;
/// A peak: the largest response within this fraction of its frequency,
/// at least [`MIN_PEAK`] times the rigid response.
const PEAK_BAND: f64 = 0.1;
const MIN_PEAK: f64 = 3.0;
/// The ring-down burst (s), and how long it is followed (s).
const BURST_S: f64 = 1.0;
const RING_S: f64 = 2.0;

/// The excitation of one axis: a linear chirp whose acceleration amplitude
/// grows with frequency, as Klipper's `accel_per_hz`, cut to the ceilings.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Sweep {
    pub from_hz: f64,
    pub to_hz: f64,
    pub duration_s: f64,
    /// Acceleration amplitude per Hz (m/s² per Hz; Klipper's 75 mm/s²/Hz).
    pub accel_per_hz: f64,
}

impl Default for Sweep {
    fn default() -> Self {
        Self {
            from_hz: 10.0,
            to_hz: 130.0,
            duration_s: 20.0,
            accel_per_hz: 0.075,
        }
    }
}

/// Why the resonances cannot be measured.
#[derive(Debug, thiserror::Error)]
pub enum ResonanceError {
    #[error("the flexible plant: {0}")]
    Plant(#[from] FlexError),
    #[error("the pose: {0}")]
    Pose(#[from] KinematicsError),
    #[error("the sweep {from_hz}–{to_hz} Hz over {duration_s} s is not a sweep")]
    Sweep {
        from_hz: f64,
        to_hz: f64,
        duration_s: f64,
    },
    #[error("axis {}: {reason}", axis + 1)]
    Axis { axis: usize, reason: String },
}

/// One mode fitted to a peak of the response.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MeasuredMode {
    pub hz: f64,
    pub damping: f64,
    /// The response at the peak (platform acceleration per rigid-body acceleration).
    pub peak: f64,
}

/// What sweeping one axis measured.
#[derive(Clone, Debug, Serialize)]
pub struct AxisResponse {
    pub axis: usize,
    /// The chirp's largest acceleration (m/s²), jerk (m/s³) and torque (N·m).
    pub peak_accel_m_s2: f64,
    pub peak_jerk_m_s3: f64,
    pub peak_torque_nm: f64,
    /// Largest |reference − encoder| during the sweep (m).
    pub max_following_error_m: f64,
    /// The response's magnitude on a `GRID_HZ` grid from `from_hz`.
    pub from_hz: f64,
    pub step_hz: f64,
    pub magnitude: Vec<f64>,
    /// The peaks, lowest first.
    pub modes: Vec<MeasuredMode>,
    /// The lowest peak's damping ratio as it rings down after a burst at
    /// its frequency, every rotor at rest (what rings after a move).
    pub ringdown_damping: Option<f64>,
}

/// An acceleration (m/s²) as the accelerometer reads it.
fn quantised(a: [f64; 3]) -> Vector3<f64> {
    Vector3::from(a).map(|a| (a / ACCEL_COUNT_M_S2).round() * ACCEL_COUNT_M_S2)
}

/// The accelerometer's record from `from_s` on, as read along `u`.
fn along(flex: &FlexPlant, u: &Vector3<f64>, from_s: f64) -> Vec<(f64, f64)> {
    flex.accel
        .iter()
        .filter(|s| s.t_s >= from_s)
        .map(|s| (s.t_s, u.dot(&quantised(s.accel))))
        .collect()
}

/// The acceleration amplitude (m/s²) at `hz`: the sweep's, cut to the
/// velocity, acceleration and jerk ceilings.
fn amplitude(sweep: &Sweep, limits: &Limits, hz: f64) -> f64 {
    let w = 2.0 * std::f64::consts::PI * hz;
    CEILING_SHARE
        * (sweep.accel_per_hz * hz)
            .min(limits.acceleration)
            .min(limits.jerk / w)
            .min(limits.velocity * w)
}

/// The chirp's displacement (m) at `t` (s), zero outside the sweep.
fn chirp(sweep: &Sweep, limits: &Limits, scale: f64, t: f64) -> f64 {
    let d = sweep.duration_s;
    if !(0.0..=d).contains(&t) {
        return 0.0;
    }
    let rate = (sweep.to_hz - sweep.from_hz) / d;
    let hz = sweep.from_hz + rate * t;
    let phase = 2.0 * std::f64::consts::PI * (sweep.from_hz * t + rate * t * t / 2.0);
    let x = (t.min(d - t) / FADE_S).min(1.0);
    let fade = x * x * x * (10.0 - 15.0 * x + 6.0 * x * x);
    let w = 2.0 * std::f64::consts::PI * hz;
    -scale * fade * amplitude(sweep, limits, hz) / (w * w) * phase.sin()
}

/// The motion of all three joints at `t`: `axis` sweeping about `q0`, the
/// others held; the derivatives by central differences of the closed form.
fn motion(
    sweep: &Sweep,
    limits: &Limits,
    scale: f64,
    q0: Vector3<f64>,
    axis: usize,
    t: f64,
) -> JointMotion<f64> {
    let h = 1e-4;
    let x = |dt: f64| chirp(sweep, limits, scale, t + dt);
    let (xm2, xm1, x0, xp1, xp2) = (x(-2.0 * h), x(-h), x(0.0), x(h), x(2.0 * h));
    let mut m = JointMotion {
        q: q0,
        ..JointMotion::default()
    };
    m.q[axis] += x0;
    m.qd[axis] = (xp1 - xm1) / (2.0 * h);
    m.qdd[axis] = (xp1 - 2.0 * x0 + xm1) / (h * h);
    m.qddd[axis] = (xp2 - 2.0 * xp1 + 2.0 * xm1 - xm2) / (2.0 * h * h * h);
    m
}

/// A burst of `accel` (m/s²) at `hz` on `axis` about `q0`, faded in and
/// out, [`BURST_S`] long.
fn burst(q0: Vector3<f64>, axis: usize, hz: f64, accel: f64, t: f64) -> JointMotion<f64> {
    let w = 2.0 * std::f64::consts::PI * hz;
    let x = |t: f64| {
        if !(0.0..=BURST_S).contains(&t) {
            return 0.0;
        }
        let f = (t.min(BURST_S - t) / 0.2).min(1.0);
        f * f * (3.0 - 2.0 * f) * accel / (w * w) * (w * t).sin()
    };
    let h = 1e-4;
    let mut m = JointMotion {
        q: q0,
        ..JointMotion::default()
    };
    m.q[axis] += x(t);
    m.qd[axis] = (x(t + h) - x(t - h)) / (2.0 * h);
    m.qdd[axis] = (x(t + h) - 2.0 * x(t) + x(t - h)) / (h * h);
    m
}

/// The amplitude at `hz` of `(t, x)` samples over `[from, from + window]`.
fn amplitude_at(samples: &[(f64, f64)], from: f64, window: f64, hz: f64) -> f64 {
    let w: Vec<&(f64, f64)> = samples
        .iter()
        .filter(|s| s.0 >= from && s.0 < from + window)
        .collect();
    if w.is_empty() {
        return 0.0;
    }
    let omega = 2.0 * std::f64::consts::PI * hz;
    let (re, im) = w.iter().fold((0.0, 0.0), |(re, im), (t, x)| {
        let ph = omega * (t - from);
        (re + x * ph.cos(), im + x * ph.sin())
    });
    2.0 * (re * re + im * im).sqrt() / w.len() as f64
}

/// The damping ratio of the decay at `hz` of `samples` after `from` (s):
/// the slope of the log amplitude over windows of two periods while it
/// stays above `floor`, by least squares; none for fewer than three windows.
fn decay(samples: &[(f64, f64)], from: f64, hz: f64, floor: f64) -> Option<f64> {
    let window = 2.0 / hz;
    let mut points = Vec::new();
    let mut t = from;
    loop {
        let a = amplitude_at(samples, t, window, hz);
        if a <= floor || t + window > samples.last()?.0 {
            break;
        }
        points.push((t, a.ln()));

        t += window;
    }
    if points.len() < 3 {
        return None;
    }
    let n = points.len() as f64;
    let (mt, ml) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), p| (a + p.0 / n, b + p.1 / n));
    let (sxy, sxx) = points.iter().fold((0.0, 0.0), |(a, b), p| {
        (a + (p.0 - mt) * (p.1 - ml), b + (p.0 - mt) * (p.0 - mt))
    });
    let sigma = -sxy / sxx;
    let wd = 2.0 * std::f64::consts::PI * hz;
    (sigma > 0.0).then(|| sigma / (sigma * sigma + wd * wd).sqrt())
}

/// Σ x(t) e^{−jωt} Δt over uniformly spaced samples `(t, x)`.
fn transform(samples: &[(f64, f64)], hz: f64) -> Complex<f64> {
    let Some(&(t0, _)) = samples.first() else {
        return Complex::new(0.0, 0.0);
    };
    let dt = match samples.last() {
        Some(&(t1, _)) if samples.len() > 1 => (t1 - t0) / (samples.len() - 1) as f64,
        _ => 1.0,
    };
    let w = 2.0 * std::f64::consts::PI * hz;
    let step = Complex::from_polar(1.0, -w * dt);
    let mut sum = Complex::new(0.0, 0.0);
    let mut z = Complex::new(0.0, 0.0);
    for (k, &(t, x)) in samples.iter().enumerate() {
        // The phasor recomputed now and then, so rounding cannot drift.
        z = if k % 1024 == 0 {
            Complex::from_polar(1.0, -w * t)
        } else {
            z * step
        };
        sum += z * x;
    }
    sum * dt
}

/// A damped second-order mode fitted to the response `h` at `hz` (a
/// rational fit, H(s)·(s² + a₁s + a₀) = b₀ + b₁s + b₂s², by linear least
/// squares reweighted by the last denominator, Sanathanan–Koerner): its
/// frequency (Hz) and damping ratio, none when the fit is not a mode.
fn fit_mode(hz: &[f64], h: &[Complex<f64>]) -> Option<(f64, f64)> {
    let centre = hz[hz.len() / 2];
    let (mut a0, mut a1) = (1.0, 0.0);
    let mut first = true;
    for _ in 0..4 {
        let mut m = DMatrix::zeros(2 * hz.len(), 5);
        let mut b = DVector::zeros(2 * hz.len());
        for (k, (&f, &hk)) in hz.iter().zip(h).enumerate() {
            let s = Complex::new(0.0, f / centre);
            let weight = if first {
                1.0
            } else {
                1.0 / (s * s + s * a1 + a0).norm()
            };
            let cols = [hk, hk * s, -Complex::new(1.0, 0.0), -s, -(s * s)];
            let rhs = -hk * s * s;
            for (c, v) in cols.iter().enumerate() {
                m[(2 * k, c)] = v.re * weight;
                m[(2 * k + 1, c)] = v.im * weight;
            }
            b[2 * k] = rhs.re * weight;
            b[2 * k + 1] = rhs.im * weight;
        }
        let x = m.svd(true, true).solve(&b, 1e-12).ok()?;
        (a0, a1) = (x[0], x[1]);
        first = false;
    }
    if a0.is_nan() || a0 <= 0.0 {
        return None;
    }
    let wn = a0.sqrt();
    let damping = a1 / (2.0 * wn);
    let f = wn * centre;
    let inside = f >= hz[0] && f <= hz[hz.len() - 1];
    // An undamped fit is noise on the accelerometer's counts, not a mode.
    (inside && damping > 1e-3 && damping < 0.5).then_some((f, damping))
}

/// The peaks of `h` (on the grid from `from_hz`), each fitted.
fn peaks(from_hz: f64, h: &[Complex<f64>]) -> Vec<MeasuredMode> {
    let mag: Vec<f64> = h.iter().map(|c| c.norm()).collect();
    let at = |k: usize| from_hz + GRID_HZ * k as f64;
    let mut out = Vec::new();
    for k in 0..mag.len() {
        let f = at(k);
        let lo = ((f * (1.0 - PEAK_BAND) - from_hz) / GRID_HZ).max(0.0) as usize;
        let hi = (((f * (1.0 + PEAK_BAND) - from_hz) / GRID_HZ) as usize).min(mag.len() - 1);
        let biggest = mag[lo..=hi].iter().all(|&m| m <= mag[k]);
        // A peak at the grid's ends is a slope, not a peak.
        if !biggest || mag[k] < MIN_PEAK || k == 0 || k + 1 == mag.len() {
            continue;
        }
        let hz: Vec<f64> = (lo..=hi).map(at).collect();
        if let Some((hz, damping)) = fit_mode(&hz, &h[lo..=hi]) {
            out.push(MeasuredMode {
                hz,
                damping,
                peak: mag[k],
            });
        }
    }
    out
}

/// Sweeps each axis of `machine` with the platform at `r` (m) on the
/// flexible plant built from the machine file's `[vibration]`.
pub fn measure(
    machine: &Machine,
    r: Vector3<f64>,
    sweep: &Sweep,
) -> Result<Vec<AxisResponse>, ResonanceError> {
    let ok = |x: f64| x.is_finite() && x > 0.0;
    if !(ok(sweep.from_hz)
        && ok(sweep.duration_s)
        && ok(sweep.accel_per_hz)
        && sweep.to_hz > sweep.from_hz + 1.0
        && sweep.duration_s > 4.0 * FADE_S
        && sweep.to_hz.is_finite())
    {
        return Err(ResonanceError::Sweep {
            from_hz: sweep.from_hz,
            to_hz: sweep.to_hz,
            duration_s: sweep.duration_s,
        });
    }
    let params = FlexParams::for_machine(machine);
    let model = machine.robot.model::<f64>();
    let pose = Pose::from_cartesian(&model, r)?;
    let q0 = pose.q;
    // Each run starts from a fresh flexible plant at rest at the pose.
    let fresh_plant = || -> Result<PlantModel, FlexError> {
        Ok(PlantModel::Flexible(FlexPlant::new(
            &machine.robot,
            PlantConfig::default(),
            params.clone(),
            q0,
        )?))
    };
    let c = machine.effective_ceilings();
    let limits = Limits {
        velocity: c.velocity,
        acceleration: c.acceleration,
        jerk: c.jerk,
        torque: c.torque,
        ..Limits::default()
    };
    let settings = machine.drive_settings();
    let configs =
        [0, 1, 2].map(|i| DriveConfig::new(&machine.robot, &limits, i, &settings, 0.5, 0.1));
    let g = pose.platform_jacobian();
    let step_s = 1e-3;
    let samples = (sweep.duration_s / step_s) as usize;
    (0..3)
        .map(|axis| {
            let bad = |reason: String| ResonanceError::Axis { axis, reason };
            // The torque ceiling: the chirp scaled down until the motion
            // (the gravity load aside) fits.
            let torques = |scale: f64| -> Result<(f64, f64), KinematicsError> {
                let held =
                    dynamics::torque(&model, &q0, &Vector3::zeros(), &Vector3::zeros())?.amax();
                let mut peak: f64 = held;
                for k in 0..=samples {
                    let m = motion(sweep, &limits, scale, q0, axis, k as f64 * step_s);
                    peak = peak.max(dynamics::torque(&model, &m.q, &m.qd, &m.qdd)?.amax());
                }
                Ok((held, peak))
            };
            let (held, peak) = torques(1.0)?;
            let room = CEILING_SHARE * limits.torque - held;
            if room <= 0.0 {
                return Err(bad(format!(
                    "holding the platform takes {held:.3} N·m, the torque ceiling is {}",
                    limits.torque
                )));
            }
            let scale = (room / (peak - held).max(1e-12)).min(1.0);
            let reference = |t: f64| motion(sweep, &limits, scale, q0, axis, t);
            let (mut peak_a, mut peak_j, mut peak_t): (f64, f64, f64) = (0.0, 0.0, 0.0);
            for k in 0..=samples {
                let m = reference(k as f64 * step_s);
                peak_a = peak_a.max(m.qdd[axis].abs());
                peak_j = peak_j.max(m.qddd[axis].abs());
                peak_t = peak_t.max(dynamics::torque(&model, &m.q, &m.qd, &m.qdd)?.amax());
            }
            let plant = fresh_plant()?;
            let run = test_reference::run(
                plant,
                &configs,
                &reference,
                sweep.duration_s,
                HOLD_S,
                TAIL_S,
            )?;
            if run.max_error_m > settings.following_error_max {
                return Err(bad(format!(
                    "the sweep's following error {:.3} mm would stop the drive (limit {:.3} mm)",
                    run.max_error_m * 1e3,
                    settings.following_error_max * 1e3
                )));
            }
            let dt = 1.0 / f64::from(configs[0].control_rate);
            let start = (HOLD_S / dt).round() as usize;
            let rest = run.encoder_m[start][axis];
            let encoder: Vec<(f64, f64)> = run.encoder_m[start..]
                .iter()
                .enumerate()
                .map(|(k, q)| ((start + k) as f64 * dt, q[axis] - rest))
                .collect();
            let gain = g.column(axis).norm();
            let u = g.column(axis) / gain;
            let flex = run
                .plant
                .flexible()
                .ok_or_else(|| bad("no accelerometer".into()))?;
            let accel = along(flex, &u, HOLD_S);
            let n = ((sweep.to_hz - sweep.from_hz) / GRID_HZ) as usize + 1;
            let h: Vec<Complex<f64>> = (0..n)
                .map(|k| {
                    let hz = sweep.from_hz + GRID_HZ * k as f64;
                    let w = 2.0 * std::f64::consts::PI * hz;
                    let x = transform(&encoder, hz) * (-w * w * gain);
                    transform(&accel, hz) / x
                })
                .collect();
            let modes = peaks(sweep.from_hz, &h);
            let ringdown_damping = match modes.first() {
                Some(m) => {
                    // Four times the sweep's amplitude there, within the ceilings.
                    let louder = Sweep {
                        accel_per_hz: 4.0 * sweep.accel_per_hz,
                        ..sweep.clone()
                    };
                    let accel = scale * amplitude(&louder, &limits, m.hz);
                    let plant = fresh_plant()?;
                    let reference = |t: f64| burst(q0, axis, m.hz, accel, t);
                    let run =
                        test_reference::run(plant, &configs, &reference, BURST_S, HOLD_S, RING_S)?;
                    let flex = run
                        .plant
                        .flexible()
                        .ok_or_else(|| bad("no accelerometer".into()))?;
                    let read = along(flex, &u, 0.0);
                    // From 50 ms after the burst, while 2 counts above the quantisation.
                    decay(&read, run.end_s + 0.05, m.hz, 2.0 * ACCEL_COUNT_M_S2)
                }
                None => None,
            };
            Ok(AxisResponse {
                axis,
                peak_accel_m_s2: peak_a,
                peak_jerk_m_s3: peak_j,
                peak_torque_nm: peak_t,
                max_following_error_m: run.max_error_m,
                from_hz: sweep.from_hz,
                step_hz: GRID_HZ,
                magnitude: h.iter().map(|c| c.norm()).collect(),
                modes,
                ringdown_damping,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A mode's response, fitted back.
    #[test]
    fn a_second_order_response_is_fitted_back() {
        let (fn_, z) = (25.0, 0.03);
        let hz: Vec<f64> = (0..200).map(|k| 22.5 + 0.025 * k as f64).collect();
        let h: Vec<Complex<f64>> = hz
            .iter()
            .map(|f| {
                let s = Complex::new(0.0, f / fn_);
                (Complex::new(1.0, 0.0) + s * 2.0 * z) / (s * s + s * 2.0 * z + 1.0)
                    + Complex::new(0.2, 0.0)
            })
            .collect();
        let (f, d) = fit_mode(&hz, &h).unwrap();
        assert!((f - fn_).abs() < 1e-6 && (d - z).abs() < 1e-6, "{f} {d}");
        // A flat response is no mode.
        let flat = vec![Complex::new(1.0, 0.0); hz.len()];
        assert!(fit_mode(&hz, &flat).is_none());
    }

    /// A sweep that is not one is refused, not run.
    #[test]
    fn a_sweep_backwards_is_refused() {
        let sweep = Sweep {
            to_hz: 5.0,
            ..Sweep::default()
        };
        let e = measure(&Machine::default(), Vector3::new(0.0, 0.0, 0.6), &sweep).unwrap_err();
        assert!(matches!(e, ResonanceError::Sweep { .. }), "{e}");
    }

    /// The damping of the plant's mode at `hz` as it rings down in closed
    /// loop after a burst on axis 0, read from the platform's true position
    /// (which no sensor gives) at two windows.
    fn ringdown(machine: &Machine, q0: Vector3<f64>, hz: f64) -> f64 {
        let reference = |t: f64| burst(q0, 0, hz, 1.0, t);
        let settings = machine.drive_settings();
        let configs = [0, 1, 2]
            .map(|i| DriveConfig::new(&machine.robot, &Limits::default(), i, &settings, 0.5, 0.1));
        let plant = PlantModel::Flexible(
            FlexPlant::new(
                &machine.robot,
                PlantConfig::default(),
                FlexParams::for_machine(machine),
                q0,
            )
            .unwrap(),
        );
        let run =
            test_reference::run(plant, &configs, &reference, BURST_S, HOLD_S, RING_S).unwrap();
        let flex = run.plant.flexible().unwrap();
        let rest = Vector3::from(flex.accel.last().unwrap().r);
        let g = Pose::from_joints(&machine.robot.model::<f64>(), q0)
            .unwrap()
            .platform_jacobian();
        let u = g.column(0).normalize();
        let x: Vec<(f64, f64)> = flex
            .accel
            .iter()
            .map(|s| (s.t_s, u.dot(&(Vector3::from(s.r) - rest))))
            .collect();
        let (t1, t2, window) = (run.end_s + 0.3, run.end_s + 0.9, 0.2);
        let a1 = amplitude_at(&x, t1, window, hz);
        let a2 = amplitude_at(&x, t2, window, hz);
        (a1 / a2).ln() / (2.0 * std::f64::consts::PI * hz * (t2 - t1))
    }

    /// The sweep recovers the flexible plant's lowest mode within 5 % in
    /// frequency and 30 % in damping, for the default `[vibration]` and a
    /// lower, more damped platform on softer screws.
    #[test]
    fn the_sweep_finds_the_models_lowest_mode() {
        use triquint_shared::machine::Vibration;
        for vibration in [
            Vibration::default(),
            Vibration {
                screw_hz: 40.0,
                screw_damping: 0.08,
                platform_hz: 20.0,
                platform_damping: 0.06,
                current_loop_hz: 800.0,
            },
        ] {
            let machine = Machine {
                vibration,
                ..Machine::default()
            };
            let r = Vector3::new(0.0, 0.0, 0.6);
            let model = machine.robot.model::<f64>();
            let q0 = Pose::from_cartesian(&model, r).unwrap().q;
            let plant = FlexPlant::new(
                &machine.robot,
                PlantConfig::default(),
                FlexParams::for_machine(&machine),
                q0,
            )
            .unwrap();
            let model = plant.modes(plant.platform()).unwrap()[0];
            let damping = ringdown(&machine, q0, model.hz);
            eprintln!("model {model:?}, ring-down damping {damping}");
            let axes = measure(&machine, r, &Sweep::default()).unwrap();
            for a in &axes {
                let m = a.modes.first().unwrap_or_else(|| panic!("{a:?}"));
                eprintln!("axis {}: {m:?}, ring-down {:?}", a.axis, a.ringdown_damping);
                assert!(
                    (m.hz - model.hz).abs() < 0.05 * model.hz,
                    "{m:?} vs {model:?}"
                );
                let d = a.ringdown_damping.unwrap();
                assert!((d - damping).abs() < 0.3 * damping, "{d} vs {damping}");
                assert!(a.max_following_error_m < machine.drive.following_error_max);
            }
        }
    }
}
