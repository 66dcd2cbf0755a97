//! Geometry of compiled collision geoms at the standing keyframe: support points (lowest point,
//! extreme points in any direction), axis tilt, mesh vertices in world coordinates. Pure math on
//! `KeyState` (positions and row-major rotations) and compiled sizes, shared by several rules.

use crate::model::{GeomType, Robot};

pub type V3 = [f64; 3];

pub fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
pub fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
pub fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
pub fn norm(a: V3) -> f64 {
    dot(a, a).sqrt()
}

/// Column `k` of a row-major 3×3 rotation: the geom's local axis `k` in world coordinates.
pub fn col(m: &[f64; 9], k: usize) -> V3 {
    [m[k], m[3 + k], m[6 + k]]
}

/// World point of a local point.
pub fn to_world(pos: V3, m: &[f64; 9], p: V3) -> V3 {
    add(pos, add(add(scale(col(m, 0), p[0]), scale(col(m, 1), p[1])), scale(col(m, 2), p[2])))
}

/// Local coordinates of a world direction.
pub fn to_local_dir(m: &[f64; 9], d: V3) -> V3 {
    [dot(col(m, 0), d), dot(col(m, 1), d), dot(col(m, 2), d)]
}

fn sgn(x: f64) -> f64 {
    if x > 1e-12 {
        1.0
    } else if x < -1e-12 {
        -1.0
    } else {
        0.0
    }
}

/// A primitive (or mesh hull) placed in the world, enough to compute support points.
#[derive(Debug, Clone)]
pub struct Placed {
    pub gtype: GeomType,
    pub size: V3,
    pub pos: V3,
    pub mat: [f64; 9],
    /// World vertices, for meshes.
    pub verts: Vec<V3>,
}

impl Placed {
    pub fn of(robot: &Robot, g: usize) -> Placed {
        let geom = &robot.geoms[g];
        let pos = robot.key.geom_xpos[g];
        let mat = robot.key.geom_xmat[g];
        let verts = if geom.gtype == GeomType::Mesh {
            mesh_world_vertices(robot, geom.mesh, pos, &mat)
        } else {
            Vec::new()
        };
        Placed { gtype: geom.gtype, size: geom.size, pos, mat, verts }
    }

    /// The point of the shape farthest along direction `d` (unit vector). Ties (a capsule lying
    /// flat, a box face) resolve to the middle of the touching segment or face.
    pub fn support(&self, d: V3) -> V3 {
        let (c, m, s) = (self.pos, &self.mat, self.size);
        match self.gtype {
            GeomType::Sphere => add(c, scale(d, s[0])),
            GeomType::Capsule => {
                let a = col(m, 2);
                add(add(c, scale(a, sgn(dot(a, d)) * s[1])), scale(d, s[0]))
            }
            GeomType::Cylinder => {
                let a = col(m, 2);
                let e = add(c, scale(a, sgn(dot(a, d)) * s[1]));
                let radial = sub(d, scale(a, dot(a, d)));
                let n = norm(radial);
                if n < 1e-9 { e } else { add(e, scale(radial, s[0] / n)) }
            }
            GeomType::Box => {
                let mut p = c;
                // Axis k of the rotation with half-size k.
                #[allow(clippy::needless_range_loop)]
                for k in 0..3 {
                    let ax = col(m, k);
                    p = add(p, scale(ax, sgn(dot(ax, d)) * s[k]));
                }
                p
            }
            GeomType::Ellipsoid => {
                let dl = to_local_dir(m, d);
                let s2 = [s[0] * s[0] * dl[0], s[1] * s[1] * dl[1], s[2] * s[2] * dl[2]];
                let den = dot(dl, s2).sqrt().max(1e-12);
                to_world(c, m, scale(s2, 1.0 / den))
            }
            GeomType::Mesh => {
                let best = self.verts.iter().map(|v| dot(*v, d)).fold(f64::NEG_INFINITY, f64::max);
                // Centroid of the vertices within 0.1 mm of the extreme, so flat faces resolve to their middle.
                let near: Vec<&V3> =
                    self.verts.iter().filter(|v| dot(**v, d) >= best - 1e-4).collect();
                if near.is_empty() {
                    return c;
                }
                let sum = near.iter().fold([0.0; 3], |acc, v| add(acc, **v));
                scale(sum, 1.0 / near.len() as f64)
            }
            _ => c,
        }
    }

    /// Lowest point (minimum world z).
    pub fn lowest(&self) -> V3 {
        self.support([0.0, 0.0, -1.0])
    }

    /// Points where the shape would touch a horizontal floor at its lowest height, within
    /// `window` metres: capsule end-sphere bottoms, box corners, mesh vertices, cylinder cap rims.
    pub fn ground_points(&self, window: f64) -> Vec<V3> {
        let down = [0.0, 0.0, -1.0];
        let (c, m, s) = (self.pos, &self.mat, self.size);
        let cands: Vec<V3> = match self.gtype {
            GeomType::Sphere | GeomType::Ellipsoid => vec![self.lowest()],
            GeomType::Capsule => {
                let a = col(m, 2);
                [-1.0, 1.0]
                    .iter()
                    .map(|k| add(add(c, scale(a, k * s[1])), scale(down, s[0])))
                    .collect()
            }
            GeomType::Cylinder => {
                let a = col(m, 2);
                let radial = sub(down, scale(a, dot(a, down)));
                let n = norm(radial);
                let r = if n < 1e-9 { [0.0; 3] } else { scale(radial, s[0] / n) };
                [-1.0, 1.0].iter().map(|k| add(add(c, scale(a, k * s[1])), r)).collect()
            }
            GeomType::Box => {
                let mut v = Vec::new();
                for i in [-1.0, 1.0] {
                    for j in [-1.0, 1.0] {
                        for k in [-1.0, 1.0] {
                            v.push(to_world(c, m, [i * s[0], j * s[1], k * s[2]]));
                        }
                    }
                }
                v
            }
            GeomType::Mesh => self.verts.clone(),
            _ => Vec::new(),
        };
        let zmin = self.lowest()[2];
        cands.into_iter().filter(|p| p[2] <= zmin + window).collect()
    }

    /// Whether this is a box lying on its largest face: the face nearest the ground (across the
    /// box axis closest to vertical) is the one across its thinnest dimension — a plate, a sole.
    /// A shank or bar box standing on an end face is none, at any tilt.
    pub fn plate_face_down(&self) -> bool {
        let m = &self.mat;
        let k = (0..3).max_by(|&a, &b| col(m, a)[2].abs().total_cmp(&col(m, b)[2].abs()));
        let thin = (0..3).min_by(|&a, &b| self.size[a].total_cmp(&self.size[b]));
        self.gtype == GeomType::Box && k.is_some() && k == thin
    }

    /// The points of the shape's flat contact feature when it faces the ground within
    /// `max_tilt` radians ([`tilt`]): a box's four corners of the face closest to facing down,
    /// a lying capsule's or cylinder's two ends. The sole the shape stands on once it settles
    /// flat, whatever the small tilt of the pose (which `toe-tilt` reports); empty otherwise.
    pub fn sole_points(&self, max_tilt: f64) -> Vec<V3> {
        if tilt(self.gtype, &self.mat).is_none_or(|t| t > max_tilt) {
            return Vec::new();
        }
        let (c, m, s) = (self.pos, &self.mat, self.size);
        match self.gtype {
            GeomType::Box => {
                let k = (0..3)
                    .max_by(|&a, &b| col(m, a)[2].abs().total_cmp(&col(m, b)[2].abs()))
                    .unwrap_or(2);
                let down = if col(m, k)[2] > 0.0 { -1.0 } else { 1.0 };
                let (u, v) = ((k + 1) % 3, (k + 2) % 3);
                let mut out = Vec::new();
                for i in [-1.0, 1.0] {
                    for j in [-1.0, 1.0] {
                        let mut l = [0.0; 3];
                        l[k] = down * s[k];
                        l[u] = i * s[u];
                        l[v] = j * s[v];
                        out.push(to_world(c, m, l));
                    }
                }
                out
            }
            GeomType::Capsule | GeomType::Cylinder if col(m, 2)[2].abs() < 0.5_f64.sqrt() => {
                self.ground_points(f64::INFINITY)
            }
            _ => Vec::new(),
        }
    }
}

/// World vertices of compiled mesh `mesh` placed at `pos`/`mat` (MuJoCo stores vertices in the
/// mesh frame, which the compiled geom frame already accounts for).
pub fn mesh_world_vertices(robot: &Robot, mesh: i32, pos: V3, mat: &[f64; 9]) -> Vec<V3> {
    if mesh < 0 {
        return Vec::new();
    }
    let (adr, num) = (robot.mj.mesh_vertadr(), robot.mj.mesh_vertnum());
    let vert = robot.mj.mesh_vert().as_flattened();
    let m = mesh as usize;
    let (a, n) = (adr[m].max(0) as usize, num[m].max(0) as usize);
    (a..a + n)
        .filter_map(|i| vert.get(3 * i..3 * i + 3))
        .map(|v| to_world(pos, mat, [v[0] as f64, v[1] as f64, v[2] as f64]))
        .collect()
}

/// Angle between a shape's flat contact feature and the ground, radians: for capsules and
/// cylinders lying down, the axis elevation; for boxes, the tilt of the face closest to facing
/// down. `None` for shapes without a flat feature (spheres, ellipsoids, meshes) and for upright
/// capsules/cylinders (axis closer to vertical than horizontal: they stand on a cap, not a side).
pub fn tilt(gtype: GeomType, mat: &[f64; 9]) -> Option<f64> {
    match gtype {
        GeomType::Capsule | GeomType::Cylinder => {
            let az = col(mat, 2)[2].abs().min(1.0);
            let elev = az.asin();
            if elev > std::f64::consts::FRAC_PI_4 {
                // Standing on a cap: a cylinder's cap face must be flat instead.
                if gtype == GeomType::Cylinder { Some(az.acos()) } else { None }
            } else {
                Some(elev)
            }
        }
        GeomType::Box => {
            let best = (0..3).map(|k| col(mat, k)[2].abs()).fold(0.0, f64::max).min(1.0);
            Some(best.acos())
        }
        _ => None,
    }
}

/// Convex hull of 2-D points, counter-clockwise (monotone chain); fewer than 3 distinct points
/// are returned as they are.
pub fn convex_hull(pts: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut p: Vec<[f64; 2]> = pts.to_vec();
    p.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let mut h: Vec<[f64; 2]> = Vec::new();
    for pass in 0..2 {
        let start = h.len();
        let it: Box<dyn Iterator<Item = &[f64; 2]>> =
            if pass == 0 { Box::new(p.iter()) } else { Box::new(p.iter().rev()) };
        for &q in it {
            while h.len() >= start + 2 && cross2(h[h.len() - 2], h[h.len() - 1], q) <= 0.0 {
                h.pop();
            }
            h.push(q);
        }
        h.pop();
    }
    h
}

fn cross2(o: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
}

/// Area of the convex hull of 2-D points.
pub fn hull_area(pts: &[[f64; 2]]) -> f64 {
    let h = convex_hull(pts);
    let n = h.len();
    if n < 3 {
        return 0.0;
    }
    (0..n).map(|i| h[i][0] * h[(i + 1) % n][1] - h[(i + 1) % n][0] * h[i][1]).sum::<f64>().abs()
        / 2.0
}

/// Whether `q` lies inside or on a counter-clockwise convex hull of three or more points (as
/// [`convex_hull`] returns), to within `slack` metres of its edges.
pub fn in_hull(h: &[[f64; 2]], q: [f64; 2], slack: f64) -> bool {
    let n = h.len();
    n >= 3
        && (0..n).all(|i| {
            let (a, b) = (h[i], h[(i + 1) % n]);
            let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
            len > 0.0 && cross2(a, b, q) / len >= -slack
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Row-major rotation about world y by `a` radians.
    fn rot_y(a: f64) -> [f64; 9] {
        let (s, c) = a.sin_cos();
        [c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c]
    }
    fn placed(gtype: GeomType, size: V3, pos: V3, mat: [f64; 9]) -> Placed {
        Placed { gtype, size, pos, mat, verts: vec![] }
    }

    #[test]
    fn lowest_point_of_rotated_capsule() {
        // Capsule along local z, rotated 90° about y: lies along world x, flat.
        let c = placed(
            GeomType::Capsule,
            [0.012, 0.05, 0.0],
            [0.0, 0.0, 0.1],
            rot_y(std::f64::consts::FRAC_PI_2),
        );
        let p = c.lowest();
        assert!((p[2] - 0.088).abs() < 1e-12 && p[0].abs() < 1e-12);
        // Tilted 3° from horizontal: one end dips by h·sin(3°).
        let a = std::f64::consts::FRAC_PI_2 - 3f64.to_radians();
        let c = placed(GeomType::Capsule, [0.012, 0.05, 0.0], [0.0, 0.0, 0.1], rot_y(a));
        let p = c.lowest();
        assert!((p[2] - (0.1 - 0.05 * 3f64.to_radians().sin() - 0.012)).abs() < 1e-12);
        assert!((tilt(GeomType::Capsule, &c.mat).unwrap().to_degrees() - 3.0).abs() < 1e-9);
    }

    #[test]
    fn lowest_point_of_rotated_box() {
        let b = placed(
            GeomType::Box,
            [0.1, 0.05, 0.015],
            [0.0, 0.0, 0.05],
            [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        );
        assert!((b.lowest()[2] - 0.035).abs() < 1e-12);
        assert_eq!(tilt(GeomType::Box, &b.mat), Some(0.0));
        let a = 2f64.to_radians();
        let b = placed(GeomType::Box, [0.1, 0.05, 0.015], [0.0, 0.0, 0.05], rot_y(a));
        let want = 0.05 - 0.1 * a.sin() - 0.015 * a.cos();
        assert!((b.lowest()[2] - want).abs() < 1e-12);
        assert!((tilt(GeomType::Box, &b.mat).unwrap() - a).abs() < 1e-9);
        assert_eq!(b.ground_points(1e-6).len(), 2);
    }

    #[test]
    fn cylinder_and_ellipsoid_support() {
        let cy = placed(
            GeomType::Cylinder,
            [0.03, 0.05, 0.0],
            [0.0, 0.0, 0.1],
            rot_y(std::f64::consts::FRAC_PI_2),
        );
        assert!((cy.lowest()[2] - 0.07).abs() < 1e-12);
        let e = placed(
            GeomType::Ellipsoid,
            [0.1, 0.05, 0.02],
            [0.0, 0.0, 0.1],
            rot_y(std::f64::consts::FRAC_PI_2),
        );
        // Local x (0.1) now points down.
        assert!((e.lowest()[2] - 0.0).abs() < 1e-12);
    }

    #[test]
    fn in_hull_square() {
        let h = convex_hull(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 0.5]]);
        assert_eq!(h.len(), 4);
        assert!(in_hull(&h, [0.5, 0.5], 0.0));
        assert!(in_hull(&h, [1.0, 0.5], 0.0));
        assert!(!in_hull(&h, [1.01, 0.5], 0.0));
        assert!(in_hull(&h, [1.01, 0.5], 0.02));
        assert!(!in_hull(&convex_hull(&[[0.0, 0.0], [1.0, 0.0]]), [0.5, 0.0], 0.1));
    }

    #[test]
    fn hull_area_square() {
        let pts = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 0.5]];
        assert!((hull_area(&pts) - 1.0).abs() < 1e-12);
        assert_eq!(hull_area(&[[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]), 0.0);
    }
}
