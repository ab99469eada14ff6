//! `fix mesh/surface[/stress]` and `fix wall/gran` (primitive planes and meshes).

use crate::deck::*;
use crate::physics::mc_settings::{self, MC_SETTINGS};

impl Deck {
    pub(in crate::deck) fn mesh_index(&self, fix_id: &str) -> R<usize> {
        match self.fixes.iter().find(|(n, _)| n == fix_id) {
            Some((_, FixKind::MeshSurface(m))) => Ok(*m),
            _ => Err(format!("{fix_id} is not a mesh/surface fix")),
        }
    }

    pub(in crate::deck) fn mesh_surface(&mut self, a: &[&str]) -> R<FixKind> {
        let mut file = None;
        let mut wall_type = None;
        let mut ops: Vec<(&str, Vec<f64>)> = Vec::new();
        let mut k = 4;
        while k < a.len() {
            match a[k] {
                "file" => {
                    file = Some(a.get(k + 1).ok_or("mesh: missing file name")?.to_string());
                    k += 2;
                }
                "type" => {
                    wall_type = Some(int(a.get(k + 1).ok_or("mesh: missing type")?)? as usize);
                    k += 2;
                }
                "move" => {
                    let v =
                        (1..=3).map(|d| num(a.get(k + d).ok_or("mesh move: 3 values")?)).collect::<R<_>>()?;
                    ops.push(("move", v));
                    k += 4;
                }
                "rotate" => {
                    if a.get(k + 1) != Some(&"axis") || a.get(k + 5) != Some(&"angle") {
                        return Err("mesh rotate: expected 'rotate axis X Y Z angle DEGREES'".into());
                    }
                    let v = [2, 3, 4, 6]
                        .iter()
                        .map(|d| num(a.get(k + d).ok_or("mesh rotate: 4 values")?))
                        .collect::<R<_>>()?;
                    ops.push(("rotate", v));
                    k += 7;
                }
                "scale" => {
                    ops.push(("scale", vec![num(a.get(k + 1).ok_or("mesh scale: value")?)?]));
                    k += 2;
                }
                "surface_vel" => {
                    let v = (1..=3)
                        .map(|d| num(a.get(k + d).ok_or("mesh surface_vel: 3 values")?))
                        .collect::<R<_>>()?;
                    ops.push(("surface_vel", v));
                    k += 4;
                }
                "stress" if matches!(a.get(k + 1), Some(&"on") | Some(&"off")) => k += 2,
                "verbose" | "heal" if a.get(k + 1).is_some() => k += 2,
                other => return Err(unsupported(&format!("fix {} keyword {other}", a[3]))),
            }
        }
        let file = file.ok_or("mesh/surface: 'file' is required")?;
        let t = wall_type.ok_or("mesh/surface: 'type' is required")?;
        if t < 1 || (self.ntypes > 0 && t > self.ntypes) {
            return Err(format!("mesh/surface: type {t} outside 1..{}", self.ntypes));
        }
        let raw = crate::engine::mesh::read_stl(&self.input_path(&file))?;
        let mut m = Mesh::new(a[1], t - 1, raw)?;
        let mut surface_vel = None;
        for (op, v) in ops {
            match op {
                "move" => m.translate(&Vec3::new(v[0], v[1], v[2])),
                "rotate" => m.rotate(&Vec3::new(v[0], v[1], v[2]), v[3])?,
                "surface_vel" => surface_vel = Some(Vec3::new(v[0], v[1], v[2])),
                _ => m.scale(v[0]),
            }
        }
        // LIGGGHTS sets the conveyor velocity after the mesh is placed (post_create).
        if let Some(vs) = surface_vel {
            m.set_surface_velocity(&vs);
        }
        m.stress = a[3] == "mesh/surface/stress";
        self.world.meshes.push(m);
        Ok(FixKind::MeshSurface(self.world.meshes.len() - 1))
    }

    pub(in crate::deck) fn wall_gran(&mut self, a: &[&str]) -> R<FixKind> {
        let (mut m, mut k) = Self::gran_model(a, 4)?;
        let geom = match a.get(k) {
            Some(&"primitive") => {
                if a.len() < k + 4 || a[k + 1] != "type" {
                    return Err(
                        "wall/gran primitive: expected 'type T xplane|yplane|zplane POS' or 'type T xcylinder|ycylinder|zcylinder R C1 C2'"
                            .into(),
                    );
                }
                let t = int(a[k + 2])? as usize;
                if t < 1 || (self.ntypes > 0 && t > self.ntypes) {
                    return Err(format!("wall type {t} outside 1..{}", self.ntypes));
                }
                let style = a[k + 3];
                let axis = |s: &str| ["x", "y", "z"].iter().position(|c| s.starts_with(c));
                let value = |j: usize| {
                    num(a
                        .get(k + 4 + j)
                        .ok_or_else(|| format!("wall/gran primitive {style}: missing value"))?)
                };
                match style {
                    "xplane" | "yplane" | "zplane" => {
                        let pos = value(0)?;
                        k += 5;
                        WallGeom::Plane(PlaneWall { axis: axis(style).unwrap_or(0), pos, wall_type: t - 1 })
                    }
                    "xcylinder" | "ycylinder" | "zcylinder" => {
                        let (radius, c1, c2) = (value(0)?, value(1)?, value(2)?);
                        if radius <= 0.0 {
                            return Err(format!(
                                "wall/gran primitive {style}: radius must be > 0, got {radius}"
                            ));
                        }
                        k += 7;
                        WallGeom::Cylinder(CylinderWall {
                            axis: axis(style).unwrap_or(0),
                            radius,
                            center: [c1, c2],
                            wall_type: t - 1,
                        })
                    }
                    other => return Err(unsupported(&format!("primitive wall {other}"))),
                }
            }
            Some(&"mesh") => {
                if a.get(k + 1) != Some(&"n_meshes") || a.get(k + 3) != Some(&"meshes") {
                    return Err("wall/gran mesh: expected 'n_meshes N meshes ID…'".into());
                }
                let n = int(a.get(k + 2).ok_or("n_meshes value")?)? as usize;
                let mut list = Vec::new();
                for j in 0..n {
                    list.push(
                        self.mesh_index(a.get(k + 4 + j).ok_or("wall/gran: fewer mesh IDs than n_meshes")?)?,
                    );
                }
                k += 4 + n;
                WallGeom::Meshes(list)
            }
            _ => return Err("wall/gran: expected 'primitive' or 'mesh'".into()),
        };
        // Model settings may also follow the geometry (LIGGGHTS accepts them at the end of the line).
        while k < a.len() {
            if !m.setting(a[k], a.get(k + 1).copied())? {
                return Err(unsupported(&format!("wall/gran keyword {}", a[k])));
            }
            k += 2;
        }
        m.check()?;
        // The wall runs the pair style's model: the same law and sub-models. The pair style's
        // multi-contact pass serves the walls too, so a wall may repeat its mprTest,
        // geometryTolerance, updateEvery, mcAccuracy and mcAccuracyCheck but not give other values (they would be ignored);
        // pairRadii concerns pairs only.
        let Some(p) = &self.pair else { return Err("fix wall/gran before pair_style gran".into()) };
        // Three differences are allowed, as LIGGGHTS runs them: a wall may leave out the pair
        // style's cohesion or rolling friction (or have its own), and may run `hooke` beside `hooke/hysteresis` pairs.
        if m.is_hysteresis() {
            return Err(unsupported(
                "fix wall/gran model hooke/hysteresis (the walls keep no largest-overlap history; use model hooke for the walls)",
            ));
        }
        let law = |g: &GranModel| if g.is_hysteresis() { "hooke" } else { g.name() };
        if (law(p), &p.tangential, p.surface_mc, p.hooke_options())
            != (law(&m), &m.tangential, m.surface_mc, m.hooke_options())
        {
            return Err(unsupported("a wall model different from the pair model"));
        }
        if let Some(w) = &self.wall_model {
            if (w.cohesion, w.tangential_reduce) != (m.cohesion, m.tangential_reduce) {
                return Err(unsupported("walls with different cohesion settings"));
            }
            if w.rolling != m.rolling {
                return Err(unsupported("walls with different rolling_friction settings"));
            }
        }
        self.wall_model = Some(m.clone());
        let given = MC_SETTINGS.map(|s| a.contains(&s.name()));
        mc_settings::check_wall(&m.mc_values(), &given, &p.mc_values())?;
        // The accuracy budget (`mcdem run` only) belongs to the pair style's pass too.
        let word = |key: &str| a.iter().rposition(|w| *w == key).and_then(|i| a.get(i + 1));
        let budget = [
            ("mcAccuracy", p.mc_accuracy.unwrap_or(0.0) == m.mc_accuracy.unwrap_or(0.0)),
            ("mcAccuracyCheck", p.mc_accuracy_check.unwrap_or(false) == m.mc_accuracy_check.unwrap_or(false)),
        ];
        for (key, same) in budget {
            if let (Some(x), false) = (word(key), same) {
                return Err(format!("wall/gran {key} {x} differs from the pair style's"));
            }
        }
        self.world.walls.push(WallFix { name: a[1].into(), geom });
        Ok(FixKind::Wall(self.world.walls.len() - 1))
    }
}
