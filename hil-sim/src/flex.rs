//! The flexible plant: the rigid mechanism of [`crate::plant`] with the
//! compliances a real machine has between the motor and the tool.
//!
//! Bodies: per axis the rotor (its inertia reflected through the screw, a
//! mass in joint metres) on the motor torque, joined to its slider by the
//! screw and coupling (a spring-damper k_s, c_s in joint metres); the
//! sliders and struts (the Lagrangian mechanism of `shared::lagrangian`
//! without platform and rotors); and the platform with its payload, held by
//! the struts' axial stiffness: K_p(pose) = k_a Σ d̂_i d̂_iᵀ relative to the
//! point the sliders place it at, so its three modes move with the pose. The
//! motor torque follows the command through a first-order current loop
//! (solved exactly between commands), and the screw's friction acts on the
//! rotor side, where the drive compensates it, so the modes keep the damping
//! their parameters give them. The encoder reads the rotor; the
//! accelerometer is on the platform.

use nalgebra::{Matrix3, SMatrix, SymmetricEigen, Vector3};
use serde::Serialize;
use triquint_shared::kinematics::{KinematicsError, Pose};
use triquint_shared::{Model, Robot, lagrangian};

use crate::plant::PlantConfig;

/// The compliances of the machine, as frequencies at a reference pose (what
/// an accelerometer measures) from which the stiffnesses are set once.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FlexParams {
    /// One slider on its screw and coupling, motor held, platform rigid,
    /// at the reference pose (Hz).
    pub screw_hz: f64,
    /// Damping ratio of that mode.
    pub screw_damping: f64,
    /// Lowest mode of the platform and payload on the struts, sliders held,
    /// at the reference pose (Hz).
    pub platform_hz: f64,
    /// Damping ratio of that mode (the struts' damping is proportional to
    /// their stiffness, so stiffer platform modes are damped more).
    pub platform_damping: f64,
    /// Bandwidth of the drives' current loop (Hz): the torque lags the command
    /// by a first order with this corner.
    pub current_loop_hz: f64,
    /// Sample rate of the accelerometer on the platform (Hz).
    pub accelerometer_hz: f64,
    /// Where the frequencies hold (platform centre, m).
    pub reference_pose: [f64; 3],
}

impl Default for FlexParams {
    /// The machine file's `[vibration]` defaults, declared once in shared.
    fn default() -> Self {
        Self::from_vibration(&triquint_shared::machine::Vibration::default())
    }
}

impl FlexParams {
    fn from_vibration(v: &triquint_shared::machine::Vibration) -> Self {
        Self {
            screw_hz: v.screw_hz,
            screw_damping: v.screw_damping,
            platform_hz: v.platform_hz,
            platform_damping: v.platform_damping,
            current_loop_hz: v.current_loop_hz,
            // An ADXL345's fastest rate, as Klipper's resonance tests use it.
            accelerometer_hz: 3200.0,
            reference_pose: [0.0, 0.0, 0.6],
        }
    }

    /// The machine file's `[vibration]` (its defaults are [`Default`]'s).
    pub fn for_machine(machine: &triquint_shared::machine::Machine) -> Self {
        Self::from_vibration(&machine.vibration)
    }
}

/// Why flexible parameters cannot describe a machine.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FlexError {
    #[error("flexible plant parameter `{name}` must be {rule}, got {value}")]
    Invalid {
        name: &'static str,
        rule: &'static str,
        value: f64,
    },
    #[error("the reference pose: {0}")]
    Pose(#[from] KinematicsError),
}

impl FlexParams {
    fn validate(&self) -> Result<(), FlexError> {
        let positive = |name, value: f64| {
            if value.is_finite() && value > 0.0 {
                Ok(())
            } else {
                Err(FlexError::Invalid {
                    name,
                    rule: "finite and > 0",
                    value,
                })
            }
        };
        positive("screw_hz", self.screw_hz)?;
        positive("platform_hz", self.platform_hz)?;
        positive("current_loop_hz", self.current_loop_hz)?;
        positive("accelerometer_hz", self.accelerometer_hz)?;
        for (name, value) in [
            ("screw_damping", self.screw_damping),
            ("platform_damping", self.platform_damping),
        ] {
            if !(value.is_finite() && (0.0..1.0).contains(&value)) {
                return Err(FlexError::Invalid {
                    name,
                    rule: "in [0, 1)",
                    value,
                });
            }
        }
        Ok(())
    }
}

/// One accelerometer sample: the platform's acceleration (gravity removed)
/// and, for the position figures, where the platform is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AccelSample {
    /// Plant time (s).
    pub t_s: f64,
    /// Platform acceleration (m/s²).
    pub accel: [f64; 3],
    /// Platform position (m).
    pub r: [f64; 3],
}

/// One mode of the linearised machine (motor held).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Mode {
    pub hz: f64,
    pub damping: f64,
    /// Share of the mode's kinetic energy in the platform (0–1): near 1 a
    /// platform mode, near 0 a screw mode.
    pub platform_share: f64,
}

/// The state the integrator advances.
#[derive(Clone, Copy, Debug)]
struct State {
    qm: Vector3<f64>,
    vm: Vector3<f64>,
    qs: Vector3<f64>,
    vs: Vector3<f64>,
    rp: Vector3<f64>,
    vp: Vector3<f64>,
}

impl State {
    /// self + h · d, with d a derivative (its positions are the rates).
    fn step(&self, d: &State, h: f64) -> State {
        State {
            qm: self.qm + d.qm * h,
            vm: self.vm + d.vm * h,
            qs: self.qs + d.qs * h,
            vs: self.vs + d.vs * h,
            rp: self.rp + d.rp * h,
            vp: self.vp + d.vp * h,
        }
    }
}

/// The flexible machine.
#[derive(Clone, Debug)]
pub struct FlexPlant {
    pub cfg: PlantConfig,
    pub params: FlexParams,
    /// Sliders and struts only.
    mech: Model<f64>,
    /// Rotor inertia reflected to the joint (kg).
    rotor_mass: f64,
    /// Platform and payload (kg).
    platform_mass: f64,
    /// Screw and coupling stiffness (N/m) and damping (N·s/m), per axis.
    k_screw: f64,
    c_screw: f64,
    /// Axial stiffness of one strut (N/m) and the struts' stiffness-proportional damping (s).
    k_strut: f64,
    beta_strut: f64,
    x: State,
    /// Torque commanded (N·m) and acting (N·m, lagging through the current loop).
    pub tau: Vector3<f64>,
    tau_acting: Vector3<f64>,
    pub braked: bool,
    t_s: f64,
    next_sample_s: f64,
    /// Every accelerometer sample so far.
    pub accel: Vec<AccelSample>,
}

/// The struts' axial stiffness seen by the platform at a pose: k Σ d̂ᵢd̂ᵢᵀ (N/m).
fn strut_stiffness(pose: &Pose<f64>, k_strut: f64) -> Matrix3<f64> {
    let mut s = Matrix3::zeros();
    for d in &pose.struts {
        let u = d.normalize();
        s += u * u.transpose();
    }
    s * k_strut
}

fn up() -> Vector3<f64> {
    Vector3::z()
}

impl FlexPlant {
    /// A machine whose rotors stand at `q0` (what the encoders read), the
    /// sliders and platform at rest where gravity holds them.
    pub fn new(
        nominal: &Robot,
        cfg: PlantConfig,
        params: FlexParams,
        q0: Vector3<f64>,
    ) -> Result<Self, FlexError> {
        params.validate()?;
        let full = cfg.true_robot(nominal).model::<f64>();
        let mech = Model {
            platform_mass: 0.0,
            rotor_inertia: 0.0,
            ..full
        };
        let reference = Pose::from_cartesian(&full, Vector3::from(params.reference_pose))?;
        // One slider with the platform rigid: the diagonal of the joint-space
        // mass matrix Gᵀ M(r) G without the rotors.
        let rigid_load = Model {
            rotor_inertia: 0.0,
            ..full
        };
        let g = reference.platform_jacobian();
        let mq = g.transpose() * lagrangian::mass_matrix(&rigid_load, &reference) * g;
        let m_axis = mq[(0, 0)].max(mq[(1, 1)]).max(mq[(2, 2)]);
        let ws = 2.0 * std::f64::consts::PI * params.screw_hz;
        let k_screw = ws * ws * m_axis;
        let c_screw = 2.0 * params.screw_damping * (k_screw * m_axis).sqrt();
        // The platform's lowest mode on unit strut stiffness sets k_a.
        let unit = strut_stiffness(&reference, 1.0);
        let lowest = unit.symmetric_eigenvalues().min();
        let wp = 2.0 * std::f64::consts::PI * params.platform_hz;
        let k_strut = wp * wp * full.platform_mass / lowest;
        let beta_strut = 2.0 * params.platform_damping / wp;
        let mut plant = Self {
            rotor_mass: full.rotor_inertia * full.ratio * full.ratio,
            platform_mass: full.platform_mass,
            mech,
            k_screw,
            c_screw,
            k_strut,
            beta_strut,
            x: State {
                qm: q0,
                vm: Vector3::zeros(),
                qs: q0,
                vs: Vector3::zeros(),
                rp: Vector3::zeros(),
                vp: Vector3::zeros(),
            },
            tau: Vector3::zeros(),
            tau_acting: Vector3::zeros(),
            braked: true,
            t_s: 0.0,
            next_sample_s: 0.0,
            accel: Vec::new(),
            cfg,
            params,
        };
        let (qs, rp) = plant.rest(q0)?;
        plant.x.qs = qs;
        plant.x.rp = rp;
        Ok(plant)
    }

    /// What the encoders see: the rotors (m).
    pub fn motor_q(&self) -> Vector3<f64> {
        self.x.qm
    }

    /// The sliders (m).
    pub fn slider_q(&self) -> Vector3<f64> {
        self.x.qs
    }

    /// Plant time (s): what the accelerometer's samples are stamped with.
    pub fn time_s(&self) -> f64 {
        self.t_s
    }

    /// The platform (m).
    pub fn platform(&self) -> Vector3<f64> {
        self.x.rp
    }

    /// Sliders and platform at rest with the rotors at `qm`: the screws carry
    /// the weight, the struts the platform's (a fixed point: the sag is tiny).
    pub fn rest(&self, qm: Vector3<f64>) -> Result<(Vector3<f64>, Vector3<f64>), KinematicsError> {
        let weight = self.platform_mass * self.mech.gravity;
        let mut qs = qm;
        let mut rp = Vector3::zeros();
        for _ in 0..20 {
            let pose = Pose::from_joints(&self.mech, qs)?;
            let kp = strut_stiffness(&pose, self.k_strut);
            let sag = kp
                .cholesky()
                .ok_or(KinematicsError::Singular)?
                .solve(&(up() * weight));
            rp = pose.r - sag;
            let hold = lagrangian::inverse_dynamics(
                &self.mech,
                &qs,
                &Vector3::zeros(),
                &Vector3::zeros(),
            )? * self.mech.ratio
                + pose.platform_jacobian().tr_mul(&(up() * weight));
            qs = qm - hold / self.k_screw;
        }
        Ok((qs, rp))
    }

    fn torque_at(&self, s: f64) -> Vector3<f64> {
        let tc = 1.0 / (2.0 * std::f64::consts::PI * self.params.current_loop_hz);
        self.tau + (self.tau_acting - self.tau) * (-s / tc).exp()
    }

    fn friction(&self, v: f64) -> f64 {
        -self.cfg.coulomb_n * (v / self.cfg.stiction_velocity).tanh()
            - self.cfg.viscous_n_s_per_m * v
    }

    /// The state's rates under motor torque `tau` (N·m).
    fn rates(&self, x: &State, tau: &Vector3<f64>) -> Result<State, KinematicsError> {
        let screw = (x.qm - x.qs) * self.k_screw + (x.vm - x.vs) * self.c_screw;
        let am = (tau * self.mech.ratio + x.vm.map(|v| self.friction(v)) - screw) / self.rotor_mass;
        let pose = Pose::from_joints(&self.mech, x.qs)?;
        let rk_dot = pose.cartesian_velocity(&x.vs);
        let kp = strut_stiffness(&pose, self.k_strut);
        // The struts' force on the platform; its reaction acts on the mechanism.
        let f = -(kp * ((x.rp - pose.r) + (x.vp - rk_dot) * self.beta_strut));
        let on_mech = pose.platform_jacobian().tr_mul(&(-f));
        let as_ = lagrangian::forward_dynamics(
            &self.mech,
            &x.qs,
            &x.vs,
            &Vector3::zeros(),
            &(screw + on_mech),
        )?;
        let ap = f / self.platform_mass - up() * self.mech.gravity;
        Ok(State {
            qm: x.vm,
            vm: am,
            qs: x.vs,
            vs: as_,
            rp: x.vp,
            vp: ap,
        })
    }

    fn rk4(&mut self, h: f64) -> Result<(), KinematicsError> {
        let x = self.x;
        let (t0, th, t1) = (
            self.torque_at(0.0),
            self.torque_at(h / 2.0),
            self.torque_at(h),
        );
        let k1 = self.rates(&x, &t0)?;
        let k2 = self.rates(&x.step(&k1, h / 2.0), &th)?;
        let k3 = self.rates(&x.step(&k2, h / 2.0), &th)?;
        let k4 = self.rates(&x.step(&k3, h), &t1)?;
        let x = x.step(&k1, h / 6.0);
        let x = x.step(&k2, h / 3.0);
        let x = x.step(&k3, h / 3.0);
        self.x = x.step(&k4, h / 6.0);
        self.tau_acting = t1;
        self.t_s += h;
        Ok(())
    }

    fn sample(&mut self) -> Result<(), KinematicsError> {
        let tau = self.torque_at(0.0);
        let a = if self.braked {
            Vector3::zeros()
        } else {
            self.rates(&self.x, &tau)?.vp
        };
        let r = self.x.rp;
        self.accel.push(AccelSample {
            t_s: self.t_s,
            accel: [a.x, a.y, a.z],
            r: [r.x, r.y, r.z],
        });
        self.next_sample_s += 1.0 / self.params.accelerometer_hz;
        Ok(())
    }

    /// Integrates `dt` seconds with RK4 steps no longer than `max_step_s`,
    /// sampling the accelerometer on its own clock.
    pub fn advance(&mut self, dt: f64) -> Result<(), KinematicsError> {
        if dt <= 0.0 {
            return Ok(());
        }
        let end = self.t_s + dt;
        loop {
            if self.next_sample_s <= self.t_s + 1e-12 {
                self.sample()?;
            }
            let until = end.min(self.next_sample_s);
            let span = until - self.t_s;
            if span <= 1e-12 {
                if until >= end - 1e-12 {
                    break;
                }
                continue;
            }
            if self.braked {
                self.x.vm = Vector3::zeros();
                self.x.vs = Vector3::zeros();
                self.x.vp = Vector3::zeros();
                self.tau_acting = self.torque_at(span);
                self.t_s = until;
                continue;
            }
            let n = (span / self.cfg.max_step_s).ceil().max(1.0) as usize;
            let h = span / n as f64;
            for _ in 0..n {
                self.rk4(h)?;
            }
            self.t_s = until;
        }
        Ok(())
    }

    /// The residual vibration over `window_s` from `from_s` (plant time),
    /// the rotors held at `qm` (m): the platform's rest and lowest mode there.
    pub fn residual(
        &self,
        from_s: f64,
        window_s: f64,
        qm: Vector3<f64>,
    ) -> Result<Option<crate::vibration::Residual>, KinematicsError> {
        let (_, rest) = self.rest(qm)?;
        let lowest = self.modes(rest)?.first().map(|m| m.hz);
        Ok(crate::vibration::residual(
            &self.accel,
            from_s,
            window_s,
            rest,
            lowest,
        ))
    }

    /// The modes of the machine linearised at the platform pose `r` with
    /// the motors held (the rotor is two orders of magnitude heavier than
    /// what it carries, and the servo holds it besides): sliders and
    /// platform, six modes, lowest first.
    pub fn modes(&self, r: Vector3<f64>) -> Result<Vec<Mode>, KinematicsError> {
        let pose = Pose::from_cartesian(&self.mech, r)?;
        let g = pose.platform_jacobian();
        let mq = g.transpose() * lagrangian::mass_matrix(&self.mech, &pose) * g;
        let kp = strut_stiffness(&pose, self.k_strut);
        let mut m = SMatrix::<f64, 6, 6>::zeros();
        let mut k = SMatrix::<f64, 6, 6>::zeros();
        let mut c = SMatrix::<f64, 6, 6>::zeros();
        m.fixed_view_mut::<3, 3>(0, 0).copy_from(&mq);
        m.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&(Matrix3::identity() * self.platform_mass));
        for (out, spring, strut) in [
            (&mut k, self.k_screw, kp),
            (&mut c, self.c_screw, kp * self.beta_strut),
        ] {
            let gkg = g.transpose() * strut * g + Matrix3::identity() * spring;
            out.fixed_view_mut::<3, 3>(0, 0).copy_from(&gkg);
            out.fixed_view_mut::<3, 3>(0, 3)
                .copy_from(&(-(g.transpose() * strut)));
            out.fixed_view_mut::<3, 3>(3, 0).copy_from(&(-(strut * g)));
            out.fixed_view_mut::<3, 3>(3, 3).copy_from(&strut);
        }
        let l = m.cholesky().ok_or(KinematicsError::Singular)?;
        let l_inv = l.l().try_inverse().ok_or(KinematicsError::Singular)?;
        let a = l_inv * k * l_inv.transpose();
        let eig = SymmetricEigen::new((a + a.transpose()) * 0.5);
        let mut modes: Vec<Mode> = (0..6)
            .map(|i| {
                let w = eig.eigenvalues[i].max(0.0).sqrt();
                // Mass-normalised shape in the physical coordinates.
                let phi = l_inv.transpose() * eig.eigenvectors.column(i);
                let kinetic = (phi.transpose() * m * phi)[(0, 0)];
                let platform = phi.fixed_rows::<3>(3).norm_squared() * self.platform_mass;
                Mode {
                    hz: w / (2.0 * std::f64::consts::PI),
                    damping: (phi.transpose() * c * phi)[(0, 0)] / (2.0 * w),
                    platform_share: platform / kinetic,
                }
            })
            .collect();
        modes.sort_by(|a, b| a.hz.total_cmp(&b.hz));
        Ok(modes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_machine_file_gives_the_default_parameters() {
        use triquint_shared::machine::Machine;
        assert_eq!(
            FlexParams::for_machine(&Machine::default()),
            FlexParams::default()
        );
        let mut m = Machine::default();
        m.vibration.platform_hz = 42.0;
        m.vibration.screw_damping = 0.08;
        let f = FlexParams::for_machine(&m);
        assert_eq!((f.platform_hz, f.screw_damping), (42.0, 0.08));
    }

    fn quiet() -> PlantConfig {
        PlantConfig {
            coulomb_n: 0.0,
            viscous_n_s_per_m: 0.0,
            ..PlantConfig::default()
        }
    }

    fn at(r: [f64; 3]) -> Vector3<f64> {
        let m = Robot::default().model::<f64>();
        Pose::from_cartesian(&m, Vector3::from(r)).unwrap().q
    }

    #[test]
    fn the_reference_pose_has_the_parameters_frequencies() {
        let p = FlexParams::default();
        let plant =
            FlexPlant::new(&Robot::default(), quiet(), p.clone(), at(p.reference_pose)).unwrap();
        let modes = plant.modes(Vector3::from(p.reference_pose)).unwrap();
        // The lowest pair is the lateral platform mode, a little below its
        // uncoupled value (the screws give too), damped about as set.
        let low = modes[0];
        assert!(low.platform_share > 0.8, "{modes:?}");
        assert!((modes[1].hz - low.hz).abs() < 1e-6 * low.hz, "{modes:?}");
        assert!(
            low.hz < p.platform_hz && low.hz > 0.75 * p.platform_hz,
            "{modes:?}"
        );
        assert!((low.damping - p.platform_damping).abs() < 0.01, "{modes:?}");
        // Then the vertical platform mode, on the screws and the steep struts.
        assert!(
            modes[2].platform_share > 0.5 && modes[2].hz > p.screw_hz,
            "{modes:?}"
        );
        // And the sliders on their screws, above the uncoupled figure (each
        // slider alone is lighter than with the platform).
        assert!(
            modes[3..]
                .iter()
                .all(|m| m.platform_share < 0.5 && m.hz > p.screw_hz),
            "{modes:?}"
        );
        assert!(
            modes.iter().all(|m| m.damping > 0.01 && m.damping < 0.15),
            "{modes:?}"
        );
    }

    #[test]
    fn at_rest_it_stays_at_rest() {
        let p = FlexParams::default();
        let q0 = at([0.02, -0.01, 0.62]);
        let mut plant = FlexPlant::new(&Robot::default(), quiet(), p, q0).unwrap();
        // Motor torque that holds the weight: the screws' force.
        let hold = (plant.motor_q() - plant.slider_q()) * plant.k_screw / plant.mech.ratio;
        plant.tau = hold;
        plant.tau_acting = hold;
        plant.braked = false;
        let r0 = plant.platform();
        plant.advance(0.2).unwrap();
        assert!(
            (plant.platform() - r0).norm() < 1e-8,
            "{}",
            (plant.platform() - r0).norm()
        );
        let peak = plant
            .accel
            .iter()
            .map(|s| Vector3::from(s.accel).norm())
            .fold(0.0, f64::max);
        assert!(peak < 1e-5, "{peak}");
        // 0.2 s at 3200 Hz, the first sample at 0.
        assert_eq!(plant.accel.len(), 641);
    }

    #[test]
    fn a_released_platform_rings_at_its_lowest_mode() {
        // Motors locked by a huge rotor: the platform, pushed sideways,
        // rings at the linearised model's lateral frequency.
        let p = FlexParams::default();
        let r = Vector3::new(0.03, 0.02, 0.58);
        let q0 = at([r.x, r.y, r.z]);
        let mut plant = FlexPlant::new(&Robot::default(), quiet(), p, q0).unwrap();
        plant.rotor_mass *= 1e6;
        let hold = (plant.motor_q() - plant.slider_q()) * plant.k_screw / plant.mech.ratio;
        plant.tau = hold;
        plant.tau_acting = hold;
        plant.braked = false;
        let modes = plant.modes(plant.platform()).unwrap();
        plant.x.rp += Vector3::new(20e-6, 0.0, 0.0);
        plant.advance(1.0).unwrap();
        let x: Vec<(f64, f64)> = plant.accel.iter().map(|s| (s.t_s, s.accel[0])).collect();
        let hz = crate::vibration::dominant_hz(&x).unwrap();
        let nearest = modes
            .iter()
            .map(|m| (m.hz - hz).abs() / m.hz)
            .fold(f64::INFINITY, f64::min);
        assert!(nearest < 0.02, "measured {hz} Hz, modes {modes:?}");
    }
}
