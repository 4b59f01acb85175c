//! `scene.offset`: moving a whole case away from the origin.
//!
//! Real programs keep world coordinates in f32, so a scene 1e5 m from the origin has
//! positions whose spacing is about 8 mm. umbra models exactly that: each coordinate is offset
//! in f64 and rounded once to f32, and everything downstream (tessellation, the truth, every
//! backend) sees the rounded case. Directions (normals, up vectors, angles) do not move.

use crate::format::{Case, Light, Object, Transform, V3};

/// The case with its `scene.offset` applied to every position, and the offset reset to zero.
pub fn apply_offset(case: &Case) -> Case {
    let o = case.scene.offset;
    let mut c = case.clone();
    if o == [0.0; 3] {
        return c;
    }
    c.scene.offset = [0.0; 3];
    let mv = |p: &mut V3| {
        for k in 0..3 {
            p[k] = (f64::from(p[k]) + f64::from(o[k])) as f32;
        }
    };
    for object in &mut c.scene.objects {
        // A transformed primitive moves through its translation (the transform applies last);
        // a plain one moves its own coordinates.
        let (transform, own): (&mut Option<Transform>, Vec<&mut V3>) = match object {
            Object::Plane(p) => (&mut p.transform, vec![&mut p.point]),
            Object::Box(b) => (&mut b.transform, vec![&mut b.center]),
            Object::Sphere(s) => (&mut s.transform, vec![&mut s.center]),
            Object::Cylinder(c) => (&mut c.transform, vec![&mut c.center]),
            Object::Mesh(m) => (&mut m.transform, m.positions.iter_mut().collect()),
        };
        match transform {
            Some(t) => mv(&mut t.translate),
            None => own.into_iter().for_each(mv),
        }
    }
    mv(&mut c.camera.eye);
    mv(&mut c.camera.target);
    // Every light moves with the scene (once only the first did, and a case of several
    // lights with an offset lit a moved scene from where its other lights had been).
    for light in &mut c.lights {
        match light {
            Light::Directional(d) => {
                if let Some(p) = &mut d.position {
                    mv(p);
                }
                mv(&mut d.target);
            }
            Light::Spot(s) => {
                mv(&mut s.position);
                mv(&mut s.target);
            }
            Light::Point(p) => mv(&mut p.position),
        }
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offset_moves_positions_and_rounds_to_f32() {
        let text = r#"{ "name": "t", "about": "t",
            "scene": { "offset": [100000.3, 0, 0], "objects": [
                { "plane": { "point": [0, 0, 0], "half_extent": 5 } },
                { "box": { "center": [0, 1, 0], "size": [1, 1, 1], "transform": { "translate": [1, 0, 0] } } } ] },
            "camera": { "eye": [0, 5, 5], "target": [0, 0, 0] },
            "light": { "spot": { "position": [0, 9, 1], "target": [0, 0, 0], "fov_y_deg": 60 } } }"#;
        let case = crate::load_str(text, std::path::Path::new("t.json")).expect("valid")[0]
            .case
            .clone();
        let c = apply_offset(&case);
        let x = (100000.3f64) as f32;
        assert_eq!(c.scene.offset, [0.0; 3]);
        let Object::Plane(p) = &c.scene.objects[0] else {
            panic!()
        };
        assert_eq!(p.point, [x, 0.0, 0.0]);
        let Object::Box(b) = &c.scene.objects[1] else {
            panic!()
        };
        // The box moves through its transform, not its centre.
        assert_eq!(b.center, [0.0, 1.0, 0.0]);
        assert_eq!(
            b.transform.as_ref().expect("transform").translate,
            [(100001.3f64) as f32, 0.0, 0.0]
        );
        assert_eq!(c.camera.eye, [x, 5.0, 5.0]);
        let Light::Spot(s) = &c.lights[0] else {
            panic!()
        };
        assert_eq!(s.position, [x, 9.0, 1.0]);
        // f32 spacing at 1e5 is 1/128: the offset is rounded, as an application's would be.
        assert_eq!(f64::from(x), 100_000.296_875);
    }

    /// Every light of several moves with the scene, and every light's run sees it moved (only
    /// the first light once did: the others lit the moved scene from where they had been).
    #[test]
    fn offset_moves_every_light_and_every_lights_run() {
        let text = r#"{ "name": "t", "about": "t",
            "scene": { "offset": [1000, 0, -500], "objects": [ { "plane": { "point": [0, 0, 0], "half_extent": 5 } } ] },
            "camera": { "eye": [0, 5, 5], "target": [0, 0, 0] },
            "shading": { "model": "dimmed" },
            "lights": [
                { "spot": { "position": [0, 9, 1], "target": [0, 0, 0], "fov_y_deg": 60 } },
                { "point": { "position": [2, 3, 0], "near": 0.2, "far": 30 } },
                { "directional": { "position": [0, 9, 0], "target": [1, 0, 0], "up": [0, 0, 1], "fit": "scene" } } ] }"#;
        let point =
            crate::load_str(text, std::path::Path::new("t.json")).expect("valid")[0].clone();
        let run = crate::Prepared::new(point);
        let at = |l: &Light| match l {
            Light::Spot(s) => (s.position, s.target),
            Light::Point(p) => (p.position, p.position),
            Light::Directional(d) => (d.position.expect("placed"), d.target),
        };
        let moved = [
            ([1000.0, 9.0, -499.0], [1000.0, 0.0, -500.0]),
            ([1002.0, 3.0, -500.0], [1002.0, 3.0, -500.0]),
            ([1000.0, 9.0, -500.0], [1001.0, 0.0, -500.0]),
        ];
        for (k, want) in moved.iter().enumerate() {
            assert_eq!(at(&run.case().lights[k]), *want, "light {k}");
            assert_eq!(at(run.lights[k].as_written()), *want, "light {k}'s run");
        }
    }
}
