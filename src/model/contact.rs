//! Contact parameters as MuJoCo combines them for a pair of geoms (`mj_contactParam` in
//! MuJoCo's `engine_collision_driver.c`): when the two priorities differ, the higher-priority
//! geom's condim, friction, solref and solimp are used; with equal priority, condim and each
//! friction coefficient are the larger of the two, solimp (and a standard, positive solref) is
//! the `solmix`-weighted mean, and a direct (non-positive) solref the elementwise minimum.
//! Explicit `<contact><pair>` elements override all of this and are not modelled here.

use super::{Geom, Robot};

/// MuJoCo's `mjMINVAL`.
const MINVAL: f64 = 1e-15;

/// The parameters of a contact between two geoms.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Combined {
    pub condim: i32,
    /// Sliding, torsional, rolling (MuJoCo duplicates sliding and rolling to five values).
    pub friction: [f64; 3],
    pub solref: [f64; 2],
    pub solimp: [f64; 5],
    /// The geom whose parameters won on priority, if the priorities differ.
    pub by_priority: Option<usize>,
}

/// The parameters MuJoCo uses for a contact between `a` and `b`.
pub fn combine(a: &Geom, b: &Geom) -> Combined {
    if a.priority != b.priority {
        let w = if a.priority > b.priority { a } else { b };
        return Combined {
            condim: w.condim,
            friction: w.friction,
            solref: w.solref,
            solimp: w.solimp,
            by_priority: Some(w.id),
        };
    }
    let mix = match (a.solmix >= MINVAL, b.solmix >= MINVAL) {
        (true, true) => a.solmix / (a.solmix + b.solmix),
        (false, false) => 0.5,
        (false, true) => 0.0,
        (true, false) => 1.0,
    };
    let solref = if a.solref[0] > 0.0 && b.solref[0] > 0.0 {
        [0, 1].map(|i| mix * a.solref[i] + (1.0 - mix) * b.solref[i])
    } else {
        [0, 1].map(|i| a.solref[i].min(b.solref[i]))
    };
    Combined {
        condim: a.condim.max(b.condim),
        friction: [0, 1, 2].map(|i| a.friction[i].max(b.friction[i])),
        solref,
        solimp: [0, 1, 2, 3, 4].map(|i| mix * a.solimp[i] + (1.0 - mix) * b.solimp[i]),
        by_priority: None,
    }
}

/// Masks allow a contact between the two geoms.
pub fn may_collide(a: &Geom, b: &Geom) -> bool {
    (a.contype & b.conaffinity) != 0 || (b.contype & a.conaffinity) != 0
}

/// The world body's colliding planes, height fields and boxes that `geom` may touch (the
/// floor, terrain): what a foot actually stands on.
pub fn ground_partners(robot: &Robot, geom: usize) -> Vec<usize> {
    use super::GeomType;
    let g = &robot.geoms[geom];
    robot
        .geoms
        .iter()
        .filter(|o| {
            o.body == 0
                && o.id != geom
                && o.collides()
                && matches!(o.gtype, GeomType::Plane | GeomType::Hfield | GeomType::Box)
                && may_collide(g, o)
        })
        .map(|o| o.id)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::GeomType;

    fn geom(id: usize, condim: i32, friction: f64, priority: i32, solmix: f64) -> Geom {
        Geom {
            id,
            name: String::new(),
            body: 0,
            gtype: GeomType::Sphere,
            size: [0.01, 0.0, 0.0],
            contype: 1,
            conaffinity: 1,
            condim,
            friction: [friction, 0.005, 0.0001],
            group: 0,
            mesh: -1,
            rbound: 0.01,
            priority,
            solmix,
            solref: [0.02, 1.0],
            solimp: [0.9, 0.95, 0.001, 0.5, 2.0],
        }
    }

    #[test]
    fn equal_priority_takes_the_larger_condim_and_friction() {
        let foot = geom(1, 1, 0.6, 0, 1.0);
        let floor = geom(0, 3, 1.0, 0, 1.0);
        let c = combine(&foot, &floor);
        assert_eq!(c.condim, 3);
        assert_eq!(c.friction[0], 1.0);
        assert_eq!(c.by_priority, None);
        assert_eq!(combine(&floor, &foot), c);
    }

    #[test]
    fn higher_priority_wins_whole() {
        let foot = geom(1, 1, 0.6, 1, 1.0);
        let floor = geom(0, 3, 1.0, 0, 1.0);
        let c = combine(&foot, &floor);
        assert_eq!((c.condim, c.friction[0], c.by_priority), (1, 0.6, Some(1)));
    }

    #[test]
    fn solref_and_solimp_mix_by_solmix() {
        let mut a = geom(1, 3, 1.0, 0, 3.0);
        let mut b = geom(0, 3, 1.0, 0, 1.0);
        a.solref = [0.04, 1.0];
        b.solref = [0.02, 2.0];
        a.solimp[0] = 0.8;
        b.solimp[0] = 0.9;
        let c = combine(&a, &b);
        assert!((c.solref[0] - 0.035).abs() < 1e-12 && (c.solref[1] - 1.25).abs() < 1e-12);
        assert!((c.solimp[0] - 0.825).abs() < 1e-12);
        // Direct (negative) solref: elementwise minimum.
        a.solref = [-1000.0, -10.0];
        b.solref = [-500.0, -20.0];
        assert_eq!(combine(&a, &b).solref, [-1000.0, -20.0]);
        // Both solmix zero: half and half.
        a.solmix = 0.0;
        b.solmix = 0.0;
        a.solimp[0] = 0.8;
        assert!((combine(&a, &b).solimp[0] - 0.85).abs() < 1e-12);
    }
}
