//! `fix ID group move/mesh mesh MESH FORM …`: the forms of LIGGGHTS 3.8 `createMeshMover`
//! (`src/mesh_mover.h`): `linear`, `wiggle`, `rotate`, `riggle`. The motion itself is
//! `engine::mesh_motion`.

use crate::deck::*;
use crate::engine::{Motion, Mover};

/// The forms and their keyword layout, for the error of a form not given right.
const FORMS: &str = "'linear VX VY VZ', 'wiggle amplitude AX AY AZ period T', \
     'rotate origin PX PY PZ axis AX AY AZ period T' or \
     'riggle origin PX PY PZ axis AX AY AZ period T amplitude DEGREES'";

impl Deck {
    pub(in crate::deck) fn move_mesh(&mut self, a: &[&str]) -> R<FixKind> {
        if a.len() < 7 || a[4] != "mesh" {
            return Err(format!("fix move/mesh: expected 'mesh ID' then {FORMS}"));
        }
        let m = self.mesh_index(a[5])?;
        if self.fixes.iter().any(|(_, k)| matches!(k, FixKind::MoveMesh(x) if *x == m)) {
            return Err(unsupported("two move/mesh fixes on one mesh"));
        }
        if !self.world.meshes[m].surface_vel.is_empty() {
            // LIGGGHTS (fix_move_mesh.cpp): the surface velocity is set once, a move every step.
            return Err(format!(
                "fix move/mesh: mesh {} has a surface_vel; LIGGGHTS refuses to move such a mesh",
                a[5]
            ));
        }
        let motion = parse_motion(&a[6..])?;
        self.world.meshes[m].mover = Some(Mover::new(motion));
        Ok(FixKind::MoveMesh(m))
    }
}

/// Reads one form (`w[0]` is its name) with its keywords in LIGGGHTS' order and count.
fn parse_motion(w: &[&str]) -> R<Motion> {
    let form = w[0];
    let layout: &[(usize, &str)] = match form {
        "linear" => &[],
        "wiggle" => &[(1, "amplitude"), (5, "period")],
        "rotate" => &[(1, "origin"), (5, "axis"), (9, "period")],
        "riggle" => &[(1, "origin"), (5, "axis"), (9, "period"), (11, "amplitude")],
        other => return Err(unsupported(&format!("fix move/mesh form {other} (only {FORMS})"))),
    };
    let len = match form {
        "linear" => 4,
        "wiggle" => 7,
        "rotate" => 11,
        _ => 13,
    };
    let bad = || format!("fix move/mesh {form}: expected {FORMS}");
    if w.len() != len {
        return Err(bad());
    }
    for &(k, key) in layout {
        if w[k] != key {
            return Err(format!("fix move/mesh {form}: expected '{key}' at \"{}\"; {}", w[k], bad()));
        }
    }
    let v3 = |k: usize| -> R<Vec3> { Ok(Vec3::new(num(w[k])?, num(w[k + 1])?, num(w[k + 2])?)) };
    let omega = |k: usize| -> R<f64> {
        let t = num(w[k])?;
        if t > 0.0 {
            Ok(std::f64::consts::TAU / t)
        } else {
            Err(format!("fix move/mesh {form}: period must be > 0, got {t}"))
        }
    };
    let axis = |k: usize| -> R<Vec3> {
        let a = v3(k)?;
        if a.norm() > 0.0 {
            Ok(a.normalize())
        } else {
            Err(format!("fix move/mesh {form}: the axis must not be zero"))
        }
    };
    Ok(match form {
        "linear" => Motion::Linear { v: v3(1)? },
        "wiggle" => Motion::Wiggle { amplitude: v3(2)?, omega: omega(6)? },
        "rotate" => Motion::Rotate { origin: v3(2)?, axis: axis(6)?, omega: omega(10)? },
        _ => Motion::Riggle {
            origin: v3(2)?,
            axis: axis(6)?,
            omega: omega(10)?,
            // LIGGGHTS reads the amplitude in degrees (MeshMoverRiggle: ampl·π/180).
            amplitude: num(w[12])?.to_radians(),
        },
    })
}
