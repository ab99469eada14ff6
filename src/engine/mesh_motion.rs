//! Rigid motion of a mesh wall under `fix move/mesh`: `linear`, `wiggle`, `rotate` and `riggle`
//! (LIGGGHTS 3.8 `src/mesh_mover_linear.cpp`, `src/mesh_mover_rotation.cpp`,
//! `src/fix_move_mesh.cpp`, `src/multi_node_mesh_I.h`).
//!
//! The rates are LIGGGHTS 3.8's: v and ω at the time since the fix was made
//! (`FixMoveMesh::time_`, summed step by step and kept across runs), applied over the step.
//! A translation moves the nodes by v dt each step, as LIGGGHTS does (an earlier form that
//! placed them from a reference by the total displacement differed from LIGGGHTS by 6e-12 of the
//! sphere velocity's range in the moving-plate deck, where this form agrees to 2e-15). A turn
//! is not applied step by step: LIGGGHTS' per-step quaternion has |q|² = 1 only to round-off,
//! and the same error every step scales the mesh steadily (measured 2e-12 after the 20 000 steps
//! of one period). The mesh is turned instead from its pose when the motion began by the summed
//! angle Σ ω dt (a compensated sum), so a full period returns it to its start to 1e-15 (test below); the two differ
//! from LIGGGHTS' positions only by that drift. The velocity field the contacts read in the step
//! is v + ω × (x − origin).

use crate::physics::Vec3;

/// One `fix move/mesh` form; angular frequencies are 2π / period.
#[derive(Debug, Clone, PartialEq)]
pub enum Motion {
    /// `linear vx vy vz`: v constant.
    Linear { v: Vec3 },
    /// `wiggle amplitude ax ay az period T`: v = A ω cos(ω t).
    Wiggle { amplitude: Vec3, omega: f64 },
    /// `rotate origin … axis … period T`: turning at ω about the (unit) axis through origin.
    Rotate { origin: Vec3, axis: Vec3, omega: f64 },
    /// `riggle origin … axis … period T amplitude A`: turning at A ω cos(ω t) about the axis (A in
    /// radians), i.e. by A sin(ω t).
    Riggle { origin: Vec3, axis: Vec3, omega: f64, amplitude: f64 },
}

impl Motion {
    /// Translational velocity and angular speed about the axis at time `t` since the fix was made.
    fn rates(&self, t: f64) -> (Vec3, f64) {
        match *self {
            Motion::Linear { v } => (v, 0.0),
            Motion::Wiggle { amplitude, omega } => (amplitude * (omega * (omega * t).cos()), 0.0),
            Motion::Rotate { omega, .. } => (Vec3::zeros(), omega),
            Motion::Riggle { omega, amplitude, .. } => (Vec3::zeros(), omega * amplitude * (omega * t).cos()),
        }
    }

    /// The axis and origin of a turning motion.
    fn pivot(&self) -> Option<(Vec3, Vec3)> {
        match *self {
            Motion::Rotate { origin, axis, .. } | Motion::Riggle { origin, axis, .. } => Some((axis, origin)),
            _ => None,
        }
    }
}

/// A mesh's node positions and contact directions at one time (the reference of a turning
/// motion).
#[derive(Debug, Clone)]
pub struct Pose {
    pub(super) tris: Vec<[Vec3; 3]>,
    pub(super) edge_dirs: Vec<Vec3>,
    pub(super) corner_dirs: Vec<Vec3>,
}

/// What one step of a mover does to its mesh: the velocity field's translation and, for a turn,
/// the mesh placed from its start pose by the angle summed since.
pub struct MotionStep<'a> {
    pub velocity: Vec3,
    pub turn: Option<Turn<'a>>,
}

/// A turning step: ω (axis × angular speed), the axis through `origin`, and the angle turned
/// since `start`, the pose the motion began from.
pub struct Turn<'a> {
    pub omega: Vec3,
    pub axis: Vec3,
    pub origin: Vec3,
    pub angle: f64,
    pub start: &'a Pose,
}

/// A `fix move/mesh` at work: its motion, the time since the fix was made and, for a turn, the
/// pose it began from and the angle turned since.
#[derive(Debug, Clone)]
pub struct Mover {
    pub motion: Motion,
    /// Summed step by step as LIGGGHTS' `time_ += dt`, so that both read the same phase.
    time: f64,
    start: Option<Pose>,
    /// Σ ω dt, summed with its round-off carried (Kahan): a plain sum of the same increment
    /// rounds the same way each step and lags by 1e-12 of a turn after 20 000 steps.
    angle: f64,
    angle_carry: f64,
}

impl Mover {
    pub fn new(motion: Motion) -> Self {
        Mover { motion, time: 0.0, start: None, angle: 0.0, angle_carry: 0.0 }
    }
}

impl Mover {
    /// One step of `dt`: the fix's clock advanced and the step's motion. `pose` gives the mesh's
    /// current pose, taken as the start the first time a turning motion steps.
    pub fn advance(&mut self, dt: f64, pose: impl FnOnce() -> Pose) -> MotionStep<'_> {
        self.time += dt;
        let (velocity, spin) = self.motion.rates(self.time);
        let turn = self.motion.pivot().map(|(axis, origin)| {
            let y = spin * dt - self.angle_carry;
            let sum = self.angle + y;
            self.angle_carry = (sum - self.angle) - y;
            self.angle = sum;
            let start = self.start.get_or_insert_with(pose);
            Turn { omega: axis * spin, axis, origin, angle: self.angle, start }
        });
        MotionStep { velocity, turn }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::mesh::Mesh;

    fn tetra() -> Mesh {
        let p = [
            Vec3::new(0.3, 0.1, 0.2),
            Vec3::new(1.1, 0.2, -0.1),
            Vec3::new(0.4, 0.9, 0.3),
            Vec3::new(0.5, 0.4, 1.2),
        ];
        let raw = vec![[p[0], p[2], p[1]], [p[0], p[1], p[3]], [p[1], p[2], p[3]], [p[0], p[3], p[2]]];
        Mesh::new("tet", 0, raw).unwrap()
    }

    fn nodes(m: &Mesh) -> Vec<Vec3> {
        m.tris.iter().flat_map(|t| t.v).collect()
    }

    /// Largest node distance between two poses relative to the largest node coordinate.
    fn moved(a: &[Vec3], b: &[Vec3]) -> f64 {
        let scale = a.iter().map(|v| v.norm()).fold(0.0, f64::max);
        a.iter().zip(b).map(|(x, y)| (x - y).norm()).fold(0.0, f64::max) / scale
    }

    /// A full period of `rotate` (20 000 steps) brings every node back to 1e-12 relative
    /// (measured 2e-16; turned step by step by LIGGGHTS' quaternion: 2e-12), a quarter period turns every node
    /// by 90° about the axis, and the wall velocity is ω × (x − origin) with |ω| = 2π/T.
    #[test]
    fn one_period_of_rotation_returns_to_the_start() {
        let mut m = tetra();
        let start = nodes(&m);
        let (period, dt) = (2.0, 1e-4);
        let origin = Vec3::new(0.1, -0.2, 0.05);
        let axis = Vec3::new(0.3, 1.0, 0.2).normalize();
        let omega = std::f64::consts::TAU / period;
        m.mover = Some(Mover::new(Motion::Rotate { origin, axis, omega }));
        let n = (period / dt).round() as u64;
        for s in 1..=n {
            m.advance_motion(dt);
            if s == n / 4 {
                for (a, b) in start.iter().zip(nodes(&m)) {
                    let (a, b) = (a - origin, b - origin);
                    let (pa, pb) = (a - axis * a.dot(&axis), b - axis * b.dot(&axis));
                    assert!((a.dot(&axis) - b.dot(&axis)).abs() < 1e-12);
                    assert!(pa.dot(&pb).abs() < 1e-12 && (axis.cross(&pa) - pb).norm() < 1e-12);
                }
            }
        }
        let back = moved(&start, &nodes(&m));
        assert!(back <= 1e-12, "after one period the nodes are {back:e} (relative) from their start");
        println!("after one period: {back:e}");
        let q = m.tris[1].v[2];
        let want = (axis * omega).cross(&(q - origin));
        assert!((m.velocity_at(1, &q) - want).norm() < 1e-14);
    }

    /// `wiggle` and `riggle` return to the start after each period and reach their amplitude a
    /// quarter period in, to O(dt) (LIGGGHTS' increments v(t) dt, v at the step's end).
    #[test]
    fn wiggle_and_riggle_follow_their_sines() {
        let (period, dt) = (0.5, 1e-5);
        let omega = std::f64::consts::TAU / period;
        let n = (period / dt).round() as u64;
        let amp = Vec3::new(0.01, 0.0, -0.02);
        let mut m = tetra();
        let start = nodes(&m);
        m.mover = Some(Mover::new(Motion::Wiggle { amplitude: amp, omega }));
        for s in 1..=n {
            m.advance_motion(dt);
            if s == n / 4 {
                let d = m.tris[2].v[1] - start[7];
                assert!((d - amp).norm() < 1e-3 * amp.norm(), "{d:?} vs {amp:?}");
            }
        }
        assert!(moved(&start, &nodes(&m)) < 1e-12);
        assert!((m.velocity - amp * omega).norm() < 1e-9 * omega);
        let mut m = tetra();
        let (origin, axis, a) = (Vec3::zeros(), Vec3::new(0.0, 0.0, 1.0), 10f64.to_radians());
        m.mover = Some(Mover::new(Motion::Riggle { origin, axis, omega, amplitude: a }));
        for _ in 0..n / 4 {
            m.advance_motion(dt);
        }
        let (p, q) = (start[7], m.tris[2].v[1]);
        let turned = p.x.atan2(p.y) - q.x.atan2(q.y);
        assert!((turned - a).abs() < 1e-3 * a, "{turned} vs {a}");
        assert!(m.omega.norm() < 1e-9);
        for _ in n / 4..n {
            m.advance_motion(dt);
        }
        assert!(moved(&start, &nodes(&m)) < 1e-12);
    }
}
