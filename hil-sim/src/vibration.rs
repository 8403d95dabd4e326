//! Residual vibration after a move: peak and RMS of the platform's
//! acceleration and of its distance from where it comes to rest, over a
//! settle window after the reference has stopped, from the flexible plant's
//! accelerometer; and the frequency that dominates a record.

use nalgebra::Vector3;
use serde::Serialize;

use crate::flex::AccelSample;

/// Default settle window after a move (s).
pub const SETTLE_WINDOW_S: f64 = 0.5;

/// The residual vibration of one move.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Residual {
    /// The window: from the end of the reference, this long (s).
    pub from_s: f64,
    pub window_s: f64,
    pub samples: usize,
    /// Largest and RMS magnitude of the platform's acceleration (m/s²).
    pub peak_accel_m_s2: f64,
    pub rms_accel_m_s2: f64,
    /// Largest and RMS distance of the platform from its rest (m).
    pub peak_position_m: f64,
    pub rms_position_m: f64,
    /// The frequency that dominates the acceleration in the window (Hz;
    /// none when the window is too short or silent).
    pub dominant_hz: Option<f64>,
    /// The machine's lowest mode at the rest pose (Hz), and the
    /// acceleration's amplitude there ([`amplitude_at`], m/s²): one mode
    /// picked out of the floor the others make.
    pub lowest_mode_hz: Option<f64>,
    pub lowest_mode_m_s2: Option<f64>,
}

/// The residual over `[from_s, from_s + window_s]` of `record`, the platform
/// coming to rest at `rest` (m), with the amplitude at `lowest_mode_hz`.
pub fn residual(
    record: &[AccelSample],
    from_s: f64,
    window_s: f64,
    rest: Vector3<f64>,
    lowest_mode_hz: Option<f64>,
) -> Option<Residual> {
    let w: Vec<&AccelSample> = record
        .iter()
        .filter(|s| s.t_s >= from_s && s.t_s <= from_s + window_s)
        .collect();
    if w.is_empty() {
        return None;
    }
    let n = w.len() as f64;
    let acc: Vec<f64> = w.iter().map(|s| Vector3::from(s.accel).norm()).collect();
    let pos: Vec<f64> = w
        .iter()
        .map(|s| (Vector3::from(s.r) - rest).norm())
        .collect();
    let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / n).sqrt();
    let peak = |v: &[f64]| v.iter().cloned().fold(0.0, f64::max);
    // The axis that moves most carries the frequency.
    let axis = (0..3)
        .max_by(|&a, &b| {
            let e = |k: usize| w.iter().map(|s| s.accel[k] * s.accel[k]).sum::<f64>();
            e(a).total_cmp(&e(b))
        })
        .unwrap_or(0);
    let trace: Vec<(f64, f64)> = w.iter().map(|s| (s.t_s, s.accel[axis])).collect();
    Some(Residual {
        from_s,
        window_s,
        samples: w.len(),
        peak_accel_m_s2: peak(&acc),
        rms_accel_m_s2: rms(&acc),
        peak_position_m: peak(&pos),
        rms_position_m: rms(&pos),
        dominant_hz: dominant_hz(&trace),
        lowest_mode_hz,
        lowest_mode_m_s2: lowest_mode_hz.map(|f| amplitude_at(record, from_s, window_s, f)),
    })
}

/// The amplitude (m/s²) of the platform's acceleration at `hz` over
/// `[from_s, from_s + window_s]`: the largest over the three axes of the
/// Fourier coefficient's magnitude, 2|Σ a e^{−iωt}|/n. Picks one mode out of
/// the noise of the others.
pub fn amplitude_at(record: &[AccelSample], from_s: f64, window_s: f64, hz: f64) -> f64 {
    let w: Vec<&AccelSample> = record
        .iter()
        .filter(|s| s.t_s >= from_s && s.t_s <= from_s + window_s)
        .collect();
    if w.is_empty() {
        return 0.0;
    }
    let omega = 2.0 * std::f64::consts::PI * hz;
    (0..3)
        .map(|k| {
            let (re, im) = w.iter().fold((0.0, 0.0), |(re, im), s| {
                let ph = omega * (s.t_s - from_s);
                (re + s.accel[k] * ph.cos(), im + s.accel[k] * ph.sin())
            });
            2.0 * (re * re + im * im).sqrt() / w.len() as f64
        })
        .fold(0.0, f64::max)
}

/// Lowest and highest frequency searched (Hz), and the grid step.
const SCAN_HZ: (f64, f64, f64) = (2.0, 400.0, 0.05);

/// The frequency of the largest peak of a Hann-windowed Fourier transform
/// of `x` (time s, value), scanned on a fine grid; none for fewer than 16
/// samples or a silent record.
pub fn dominant_hz(x: &[(f64, f64)]) -> Option<f64> {
    if x.len() < 16 {
        return None;
    }
    let n = x.len();
    let mean = x.iter().map(|p| p.1).sum::<f64>() / n as f64;
    let t0 = x[0].0;
    let span = x[n - 1].0 - t0;
    if span <= 0.0 {
        return None;
    }
    let w: Vec<(f64, f64)> = x
        .iter()
        .map(|&(t, v)| {
            let hann = 0.5 - 0.5 * (2.0 * std::f64::consts::PI * (t - t0) / span).cos();
            (t - t0, (v - mean) * hann)
        })
        .collect();
    let (lo, hi, step) = SCAN_HZ;
    // Each sample's phasor e^{iωt} is carried from one frequency to the
    // next by the constant rotation e^{i·2π·step·t} (no sin and cos per
    // sample and frequency), and set afresh every REANCHOR frequencies so
    // the products' rounding cannot build up.
    const REANCHOR: usize = 256;
    let phasor = |f: f64, t: f64| (2.0 * std::f64::consts::PI * f * t).sin_cos();
    let rot: Vec<(f64, f64)> = w.iter().map(|&(t, _)| phasor(step, t)).collect();
    let mut p: Vec<(f64, f64)> = Vec::with_capacity(n);
    let mut best: Option<(f64, f64)> = None;
    let mut k = 0usize;
    loop {
        let f = lo + k as f64 * step;
        if f > hi + 1e-9 {
            break;
        }
        if k % REANCHOR == 0 {
            p.clear();
            p.extend(w.iter().map(|&(t, _)| phasor(f, t)));
        } else {
            for (z, r) in p.iter_mut().zip(&rot) {
                *z = (z.0 * r.1 + z.1 * r.0, z.1 * r.1 - z.0 * r.0);
            }
        }
        let (mut re, mut im) = (0.0, 0.0);
        for (&(_, v), &(sin, cos)) in w.iter().zip(&p) {
            re += v * cos;
            im += v * sin;
        }
        let pw = re * re + im * im;
        if best.is_none_or(|b| pw > b.1) {
            best = Some((f, pw));
        }
        k += 1;
    }
    best.filter(|b| b.1 > 0.0).map(|b| b.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_decaying_sine_is_found_and_measured() {
        let (f, zeta, amp) = (37.3, 0.03, 0.2);
        let w = 2.0 * std::f64::consts::PI * f;
        let rec: Vec<AccelSample> = (0..3200)
            .map(|k| {
                let t = k as f64 / 3200.0;
                let a = amp * (-zeta * w * t).exp() * (w * t).sin();
                AccelSample {
                    t_s: t,
                    accel: [0.0, a, 0.0],
                    r: [0.0, -a / (w * w), 0.5],
                }
            })
            .collect();
        let r = residual(&rec, 0.0, 0.5, Vector3::new(0.0, 0.0, 0.5), Some(f)).unwrap();
        assert!(r.lowest_mode_m_s2.unwrap() > 0.1 * amp);
        assert!((r.dominant_hz.unwrap() - f).abs() < 0.2, "{r:?}");
        assert!(
            r.peak_accel_m_s2 <= amp && r.peak_accel_m_s2 > 0.8 * amp,
            "{r:?}"
        );
        assert!(r.rms_accel_m_s2 < r.peak_accel_m_s2 / 2.0_f64.sqrt());
        assert!((r.peak_position_m * w * w - r.peak_accel_m_s2).abs() < 1e-9);
        assert_eq!(r.samples, 1601);
        // A steady sine's amplitude is recovered; a far frequency sees little.
        let steady: Vec<AccelSample> = rec
            .iter()
            .map(|s| AccelSample {
                accel: [0.0, amp * (w * s.t_s).sin(), 0.0],
                ..*s
            })
            .collect();
        assert!((amplitude_at(&steady, 0.0, 1.0, f) - amp).abs() < 0.01 * amp);
        assert!(amplitude_at(&steady, 0.0, 1.0, 3.0 * f) < 0.02 * amp);
        // Nothing in the window, nothing to say.
        assert!(residual(&rec, 2.0, 0.5, Vector3::zeros(), None).is_none());
        assert_eq!(dominant_hz(&[(0.0, 1.0); 20]), None);
    }
}
