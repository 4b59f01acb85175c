//! Validation of a parsed case: every impossible or degenerate value is an error that names the
//! JSON path and the fix. Validation collects all problems instead of stopping at the first,
//! so a user fixes a file in one pass.
//!
//! Limits that are not in the specs are the harness's own and say why: map sizes stop at 16384
//! (GL_MAX_TEXTURE_SIZE of llvmpipe and lavapipe), camera images at 8192 (the reference keeps
//! several f32 buffers per pixel), PCF kernels at 15 (225 taps; wider is a blur, not a test).

use std::path::Path;

use glam::Vec3;

use crate::error::{CaseError, CaseErrors};
use crate::format::*;

/// Largest shadow-map side (GL_MAX_TEXTURE_SIZE on llvmpipe and lavapipe).
pub const MAX_MAP_SIZE: u32 = 16384;
/// Largest camera image side.
pub const MAX_IMAGE_SIZE: u32 = 8192;
/// Widest PCF kernel.
pub const MAX_PCF: u32 = 15;
/// Most cascades of a directional light: the six light matrices every backend's lit pass
/// already holds for a cube map's faces (engines ship 1 to 4).
pub const MAX_CASCADES: u32 = 6;
/// Smallest |sin| between an up hint and a view direction (about 0.06°).
const MIN_UP_SIN: f32 = 1e-3;

/// Checks `case` (read from `file`) and returns every problem found.
pub fn validate(case: &Case, file: &Path) -> Result<(), CaseErrors> {
    let mut v = Validator {
        file,
        errors: Vec::new(),
    };
    v.case(case);
    if v.errors.is_empty() {
        Ok(())
    } else {
        Err(CaseErrors(v.errors))
    }
}

/// Names of cases and twins: lower-case letters, digits, `-` and `_` (they name files), and
/// beginning with a letter or a digit: a name that begins with `-` reads as an option on
/// every command line it is passed on (`umbra render … --point -rf`, `umbra repro
/// gl33/llvmpipe/-rf`), so its own reproduce command would not run.
fn identifier(name: &str) -> bool {
    name.starts_with(|c: char| c.is_ascii_lowercase() || c.is_ascii_digit())
        && name
            .chars()
            .all(|ch| ch.is_ascii_lowercase() || ch.is_ascii_digit() || ch == '-' || ch == '_')
}

struct Validator<'a> {
    file: &'a Path,
    errors: Vec<CaseError>,
}

impl Validator<'_> {
    fn err(&mut self, path: impl Into<String>, message: impl Into<String>, fix: impl Into<String>) {
        self.errors
            .push(CaseError::new(self.file, path, message, fix));
    }

    fn finite(&mut self, path: &str, x: f32) -> bool {
        if x.is_finite() {
            return true;
        }
        self.err(
            path,
            format!("{x} is not a finite f32"),
            "use a finite number within ±3.4e38 (JSON has no NaN or infinity)",
        );
        false
    }

    /// A shader bias term: finite and ≥ 0 (a distance away from the light).
    fn bias_distance(&mut self, path: &str, x: f32) {
        if self.finite(path, x) && x < 0.0 {
            self.err(
                path,
                format!("must be ≥ 0, got {x}"),
                "bias distances point away from the light: use a positive number",
            );
        }
    }

    fn finite3(&mut self, path: &str, v: V3) -> bool {
        let mut ok = true;
        for (i, x) in v.iter().enumerate() {
            ok &= self.finite(&format!("{path}[{i}]"), *x);
        }
        ok
    }

    fn positive(&mut self, path: &str, x: f32, fix: &str) -> bool {
        if !self.finite(path, x) {
            return false;
        }
        if x <= 0.0 {
            self.err(path, format!("must be > 0, got {x}"), fix);
            return false;
        }
        true
    }

    fn unit_range(&mut self, path: &str, x: f32) {
        if self.finite(path, x) && !(0.0..=1.0).contains(&x) {
            self.err(
                path,
                format!("must be in [0, 1], got {x}"),
                "use a value from 0 to 1",
            );
        }
    }

    fn nonzero3(&mut self, path: &str, v: V3, what: &str) -> bool {
        if !self.finite3(path, v) {
            return false;
        }
        if Vec3::from(v).length_squared() == 0.0 {
            self.err(
                path,
                format!("{what} is the zero vector"),
                format!("give {what} a direction"),
            );
            return false;
        }
        true
    }

    fn near_far(&mut self, path: &str, near: f32, far: f32, perspective: bool) {
        let (pn, pf) = (format!("{path}.near"), format!("{path}.far"));
        if !(self.finite(&pn, near) & self.finite(&pf, far)) {
            return;
        }
        if perspective && near <= 0.0 {
            self.err(
                pn,
                format!("must be > 0 for a perspective projection, got {near}"),
                "use a small positive distance such as 0.1",
            );
        } else if near >= far {
            self.err(
                pf,
                format!("far ({far}) must be greater than near ({near})"),
                "make far larger than near",
            );
        }
    }

    fn fov(&mut self, path: &str, fov: f32) {
        if self.finite(path, fov) && !(fov > 0.0 && fov < 180.0) {
            self.err(
                path,
                format!("field of view must be strictly between 0 and 180 degrees, got {fov}"),
                "use a vertical field of view such as 45",
            );
        }
    }

    /// A view from `eye` to `target` with `up`: eye ≠ target and up not parallel.
    fn view(&mut self, path: &str, eye: (&str, V3), target: V3, up: V3) {
        let ok = self.finite3(&format!("{path}.{}", eye.0), eye.1)
            & self.finite3(&format!("{path}.target"), target)
            & self.nonzero3(&format!("{path}.up"), up, "up");
        if !ok {
            return;
        }
        let dir = Vec3::from(target) - Vec3::from(eye.1);
        if dir.length_squared() == 0.0 {
            self.err(
                format!("{path}.target"),
                format!(
                    "{} and target are the same point, so there is no view direction",
                    eye.0
                ),
                format!("move target away from {}", eye.0),
            );
            return;
        }
        self.up_not_parallel(path, dir, up);
    }

    fn up_not_parallel(&mut self, path: &str, dir: Vec3, up: V3) {
        let sin = dir.normalize().cross(Vec3::from(up).normalize()).length();
        if sin < MIN_UP_SIN {
            self.err(
                format!("{path}.up"),
                format!("up {up:?} is parallel to the view direction {:?}", dir.normalize().to_array()),
                "give an up vector across the view direction, e.g. [0, 0, -1] for a view straight down",
            );
        }
    }

    fn case(&mut self, c: &Case) {
        if !identifier(&c.name) {
            self.err(
                "name",
                format!("{:?} is not a valid case name", c.name),
                "use lower-case letters, digits, '-' and '_', beginning with a letter or a digit (it names files and report rows, and is passed on command lines)",
            );
        }
        if c.about.trim().is_empty() {
            self.err(
                "about",
                "is empty",
                "say in one sentence what the case checks and why",
            );
        }
        self.scene(&c.scene);
        self.camera(&c.camera);
        self.lights(c);
        self.shadow(&c.shadow);
        self.light_bias(c);
        self.shading(&c.shading);
        self.twins(&c.expect.twins);
        if let Some(path) = &c.expect.error_falls_along {
            // Sweep points have their sweep removed, so only the file itself is checked.
            if !c.sweep.is_empty() && !c.sweep.contains_key(path) {
                self.err(
                    "expect.error_falls_along",
                    format!("{path:?} is not a swept path of this case"),
                    format!(
                        "name one of the sweep's paths: {}",
                        c.sweep.keys().cloned().collect::<Vec<_>>().join(", ")
                    ),
                );
            }
        }
    }

    /// Every light, each under its own path ([`Case::light_path`]: `light` for one light,
    /// `lights[k]` for several), at most MAX_LIGHTS of them; then what several lights cannot
    /// have yet, each with its fix.
    fn lights(&mut self, c: &Case) {
        let n = c.lights.len();
        if n > MAX_LIGHTS {
            self.err(
                "lights",
                format!("{n} lights; a case with `lights` has 2 to {MAX_LIGHTS}"),
                "write one light as `light`, or remove lights (each is one lit pass and one map)",
            );
        }
        for (k, l) in c.lights.iter().enumerate() {
            let mut one = Validator {
                file: self.file,
                errors: Vec::new(),
            };
            one.light(l, &c.shadow, &c.camera);
            for mut e in one.errors {
                if let Some(rest) = e.path.strip_prefix("light") {
                    e.path = format!("{}{rest}", c.light_path(k));
                }
                self.errors.push(e);
            }
        }
        if n > 1 {
            self.several_lights(c);
        }
    }

    /// What several lights cannot have yet (cascades on one of them, a map kind the
    /// placement cannot hold, the classic model, mip levels in an array), each with its fix.
    fn several_lights(&mut self, c: &Case) {
        for (k, l) in c.lights.iter().enumerate() {
            let cascaded = matches!(l, Light::Directional(d) if d.cascades.is_some());
            if cascaded {
                self.err(
                    format!("lights[{k}].directional.cascades"),
                    "cascades are modelled for a case's one light, not for one of several",
                    "remove the cascades, or make the cascaded light the case's only `light`",
                );
            }
            if c.shadow.placement == Placement::CubeArray && !matches!(l, Light::Point(_)) {
                self.err(
                    "shadow.placement",
                    format!("lights[{k}] is not a point light, and has no cube in a cube array"),
                    "use \"array\" (spot and directional lights) or \"separate\", or make every light a point light",
                );
            }
            if c.shadow.placement == Placement::Array && matches!(l, Light::Point(_)) {
                self.err(
                    "shadow.placement",
                    format!(
                        "lights[{k}] is a point light, whose cube map has no layer of a 2D array"
                    ),
                    "use \"cube_array\" (every light a point light) or \"separate\" (a cube map per point light), or spot and directional lights",
                );
            }
        }
        if c.shading.model != ShadingModel::Dimmed {
            self.err(
                "shading.model",
                "the classic model's one shadowed factor has no meaning with several shadows",
                "use \"dimmed\" (each light's diffuse and specular terms dimmed by its own shadow)",
            );
        }
        if c.shadow.placement != Placement::Separate && c.shadow.mipmaps.is_some() {
            self.err(
                "shadow.mipmaps",
                "an array's layers have no mip levels here (as for cascades)",
                "remove shadow.mipmaps, or use \"placement\": \"separate\"",
            );
        }
    }

    fn twins(&mut self, twins: &[crate::format::Twin]) {
        let mut seen = std::collections::BTreeSet::from([crate::format::BIAS_ORDER]);
        for (i, t) in twins.iter().enumerate() {
            let p = format!("expect.twins[{i}]");
            if !identifier(&t.name) {
                self.err(
                    format!("{p}.name"),
                    format!("{:?} is not a valid twin name", t.name),
                    "use lower-case letters, digits, '-' and '_', beginning with a letter or a digit",
                );
            } else if !seen.insert(&t.name) {
                self.err(
                    format!("{p}.name"),
                    format!("the name {:?} is taken (bias-order is built in)", t.name),
                    "give each twin its own name",
                );
            }
            if t.set.is_empty() {
                self.err(
                    format!("{p}.set"),
                    "sets nothing, so the twin is the case itself",
                    "set at least one dotted path, such as \"shadow.attachments\": \"with_color\"",
                );
            }
        }
    }

    fn scene(&mut self, s: &Scene) {
        self.finite3("scene.offset", s.offset);
        if s.objects.is_empty() {
            self.err(
                "scene.objects",
                "the scene is empty",
                "add at least one object, e.g. a plane",
            );
        }
        for (i, o) in s.objects.iter().enumerate() {
            let p = format!("scene.objects[{i}]");
            match o {
                Object::Plane(pl) => {
                    let p = format!("{p}.plane");
                    self.finite3(&format!("{p}.point"), pl.point);
                    self.nonzero3(&format!("{p}.normal"), pl.normal, "normal");
                    let (hu, hv) = pl.half_extent.pair();
                    let fix = "give the plane a positive half extent";
                    self.positive(&format!("{p}.half_extent"), hu.min(hv), fix);
                    self.color(&p, pl.color);
                    self.transform(&p, &pl.transform);
                }
                Object::Box(b) => {
                    let p = format!("{p}.box");
                    self.finite3(&format!("{p}.center"), b.center);
                    for (k, s) in b.size.iter().enumerate() {
                        self.positive(
                            &format!("{p}.size[{k}]"),
                            *s,
                            "give every edge a positive length",
                        );
                    }
                    self.color(&p, b.color);
                    self.transform(&p, &b.transform);
                }
                Object::Sphere(sp) => {
                    let p = format!("{p}.sphere");
                    self.finite3(&format!("{p}.center"), sp.center);
                    self.positive(
                        &format!("{p}.radius"),
                        sp.radius,
                        "give the sphere a positive radius",
                    );
                    if !(4..=512).contains(&sp.segments) {
                        self.err(
                            format!("{p}.segments"),
                            format!("must be from 4 to 512, got {}", sp.segments),
                            "use 32 for a smooth sphere",
                        );
                    }
                    self.color(&p, sp.color);
                    self.transform(&p, &sp.transform);
                }
                Object::Cylinder(cy) => {
                    let p = format!("{p}.cylinder");
                    self.finite3(&format!("{p}.center"), cy.center);
                    self.positive(
                        &format!("{p}.radius"),
                        cy.radius,
                        "give the cylinder a positive radius",
                    );
                    self.positive(
                        &format!("{p}.height"),
                        cy.height,
                        "give the cylinder a positive height",
                    );
                    if !(3..=512).contains(&cy.segments) {
                        self.err(
                            format!("{p}.segments"),
                            format!("must be from 3 to 512, got {}", cy.segments),
                            "use 8 to 32, as engines tessellate a cylinder",
                        );
                    }
                    self.color(&p, cy.color);
                    self.transform(&p, &cy.transform);
                }
                Object::Mesh(m) => {
                    let p = format!("{p}.mesh");
                    self.mesh(&p, m);
                    self.color(&p, m.color);
                    self.transform(&p, &m.transform);
                }
            }
        }
    }

    fn mesh(&mut self, p: &str, m: &Mesh) {
        if m.triangles.is_empty() {
            self.err(
                format!("{p}.triangles"),
                "the mesh has no triangles",
                "add triangles or remove the mesh",
            );
        }
        let mut finite = true;
        for (k, v) in m.positions.iter().enumerate() {
            finite &= self.finite3(&format!("{p}.positions[{k}]"), *v);
        }
        let n = m.positions.len();
        for (k, t) in m.triangles.iter().enumerate() {
            let tp = format!("{p}.triangles[{k}]");
            if let Some(bad) = t.iter().find(|&&i| i as usize >= n) {
                self.err(
                    tp,
                    format!("index {bad} is out of range: the mesh has {n} positions"),
                    format!("use indices from 0 to {}", n.saturating_sub(1)),
                );
                continue;
            }
            if !finite {
                continue;
            }
            let [a, b, c] = t.map(|i| Vec3::from(m.positions[i as usize]));
            if (b - a).cross(c - a).length_squared() == 0.0 {
                self.err(
                    tp,
                    format!("triangle {t:?} has zero area"),
                    "remove degenerate triangles: they have no normal and cover nothing",
                );
            }
        }
    }

    fn color(&mut self, p: &str, c: V3) {
        for (k, x) in c.iter().enumerate() {
            self.unit_range(&format!("{p}.color[{k}]"), *x);
        }
    }

    fn transform(&mut self, p: &str, t: &Option<Transform>) {
        let Some(t) = t else { return };
        let p = format!("{p}.transform");
        self.finite3(&format!("{p}.translate"), t.translate);
        if let Some(r) = &t.rotate_deg {
            self.nonzero3(&format!("{p}.rotate_deg.axis"), r.axis, "the rotation axis");
            self.finite(&format!("{p}.rotate_deg.angle"), r.angle);
        }
        let s = t.scale.vec();
        for (k, x) in s.iter().enumerate() {
            let sp = match t.scale {
                Scale::Uniform(_) => format!("{p}.scale"),
                Scale::PerAxis(_) => format!("{p}.scale[{k}]"),
            };
            if self.finite(&sp, *x) && *x == 0.0 {
                self.err(
                    sp,
                    "a zero scale flattens the object",
                    "use a non-zero scale factor",
                );
                break;
            }
        }
    }

    fn camera(&mut self, c: &Camera) {
        self.view("camera", ("eye", c.eye), c.target, c.up);
        self.fov("camera.fov_y_deg", c.fov_y_deg);
        self.near_far("camera", c.near, c.far, true);
        for (k, x) in c.clear.iter().enumerate() {
            self.unit_range(&format!("camera.clear[{k}]"), *x);
        }
        for (k, s) in c.size.iter().enumerate() {
            if *s == 0 || *s > MAX_IMAGE_SIZE {
                self.err(
                    format!("camera.size[{k}]"),
                    format!("image side must be from 1 to {MAX_IMAGE_SIZE} pixels, got {s}"),
                    "use a size such as [512, 512]",
                );
            }
        }
    }

    fn light(&mut self, l: &Light, shadow: &Shadow, camera: &Camera) {
        self.emission(l);
        match l {
            Light::Directional(d) => {
                self.directional(d, camera);
                if d.cascades.is_some() && shadow.mipmaps.is_some() {
                    self.err(
                        "shadow.mipmaps",
                        "mipmapped maps are modelled for one 2D map, not a cascade array",
                        "remove shadow.mipmaps or light.directional.cascades",
                    );
                }
            }
            Light::Spot(s) => {
                self.view("light.spot", ("position", s.position), s.target, s.up);
                self.fov("light.spot.fov_y_deg", s.fov_y_deg);
                self.near_far("light.spot", s.near, s.far, true);
            }
            Light::Point(p) => {
                self.finite3("light.point.position", p.position);
                self.near_far("light.point", p.near, p.far, true);
                if shadow.mipmaps.is_some() {
                    self.err(
                        "shadow.mipmaps",
                        "mipmapped maps are modelled for 2D maps only, not a point light's cube map",
                        "use a spot or directional light, or remove shadow.mipmaps",
                    );
                }
                if shadow.size[0] != shadow.size[1] {
                    self.err(
                        "shadow.size",
                        format!(
                            "a point light's cube map needs square faces, got {:?}",
                            shadow.size
                        ),
                        "give both sides the same size, e.g. [512, 512]",
                    );
                }
            }
        }
    }

    /// The light's `color` (each channel in [0, 1]) and `intensity` (finite, ≥ 0).
    fn emission(&mut self, l: &Light) {
        let p = l.path();
        let (color, intensity) = l.emission();
        self.color(p, color);
        let ip = format!("{p}.intensity");
        if self.finite(&ip, intensity) && intensity < 0.0 {
            self.err(
                ip,
                format!("must be ≥ 0, got {intensity}"),
                "use 0 for a light that adds nothing, 1 for its colour as given",
            );
        }
    }

    fn directional(&mut self, d: &Directional, camera: &Camera) {
        let p = "light.directional";
        let by_angles = d.azimuth_deg.is_some() || d.elevation_deg.is_some();
        match (d.position, by_angles) {
            (Some(pos), false) => self.view(p, ("position", pos), d.target, d.up),
            (None, true) => {
                let (Some(az), Some(el)) = (d.azimuth_deg, d.elevation_deg) else {
                    let missing = if d.azimuth_deg.is_none() {
                        "azimuth_deg"
                    } else {
                        "elevation_deg"
                    };
                    self.err(
                        format!("{p}.{missing}"),
                        "the light is placed by angles but this one is missing",
                        "give both azimuth_deg and elevation_deg",
                    );
                    return;
                };
                let ok = self.finite(&format!("{p}.azimuth_deg"), az)
                    & self.finite(&format!("{p}.elevation_deg"), el)
                    & self.positive(
                        &format!("{p}.distance"),
                        d.distance,
                        "use a distance beyond the scene, e.g. 50",
                    )
                    & self.finite3(&format!("{p}.target"), d.target)
                    & self.nonzero3(&format!("{p}.up"), d.up, "up");
                if ok {
                    let towards = crate::light::direction_from_angles(az, el);
                    self.up_not_parallel(p, -towards, d.up);
                }
            }
            (Some(_), true) => self.err(
                format!("{p}.position"),
                "the light is placed twice: by position and by angles",
                "keep either position or azimuth_deg + elevation_deg",
            ),
            (None, false) => self.err(
                p,
                "the light has no placement",
                "give position (with target), or azimuth_deg and elevation_deg",
            ),
        }
        if let Some(c) = &d.cascades {
            self.cascades(p, d, c, camera);
            return;
        }
        match (&d.ortho, &d.fit) {
            (Some(o), None) => {
                let op = format!("{p}.ortho");
                let all = [o.left, o.right, o.bottom, o.top, o.near, o.far];
                let names = ["left", "right", "bottom", "top", "near", "far"];
                let mut ok = true;
                for (x, n) in all.iter().zip(names) {
                    ok &= self.finite(&format!("{op}.{n}"), *x);
                }
                if !ok {
                    return;
                }
                if o.left >= o.right {
                    self.err(
                        format!("{op}.right"),
                        format!("right ({}) must exceed left ({})", o.right, o.left),
                        "swap or widen the bounds",
                    );
                }
                if o.bottom >= o.top {
                    self.err(
                        format!("{op}.top"),
                        format!("top ({}) must exceed bottom ({})", o.top, o.bottom),
                        "swap or widen the bounds",
                    );
                }
                self.near_far(&op, o.near, o.far, false);
            }
            (None, Some(_)) => {}
            (Some(_), Some(_)) => self.err(
                format!("{p}.fit"),
                "both explicit bounds (ortho) and fit are given",
                "keep one: ortho for fixed bounds, or \"fit\": \"scene\"",
            ),
            (None, None) => self.err(
                format!("{p}.ortho"),
                "a directional light needs bounds",
                "give ortho {left, right, bottom, top, near, far} or \"fit\": \"scene\"",
            ),
        }
    }

    /// Cascades fit their own bounds, one set per slice of the camera's view depths.
    fn cascades(&mut self, p: &str, d: &Directional, c: &Cascades, camera: &Camera) {
        let cp = format!("{p}.cascades");
        if d.ortho.is_some() || d.fit.is_some() {
            let which = if d.ortho.is_some() { "ortho" } else { "fit" };
            self.err(
                format!("{p}.{which}"),
                "cascades fit each cascade's bounds to its slice of the camera's view",
                format!("remove {which}, or remove cascades for one map"),
            );
        }
        if c.count == 0 || c.count > MAX_CASCADES {
            self.err(
                format!("{cp}.count"),
                format!("from 1 to {MAX_CASCADES} cascades, got {}", c.count),
                "use 1 to 4, as engines do",
            );
        }
        match (c.split, c.lambda) {
            (SplitScheme::Practical, Some(l)) if !(0.0..=1.0).contains(&l) => self.err(
                format!("{cp}.lambda"),
                format!("λ blends the logarithmic (1) and uniform (0) splits, got {l}"),
                "use a value in [0, 1], e.g. 0.5",
            ),
            (SplitScheme::Practical, _) | (_, None) => {}
            (_, Some(_)) => self.err(
                format!("{cp}.lambda"),
                "lambda belongs to the practical scheme only",
                "remove lambda, or use \"split\": \"practical\"",
            ),
        }
        self.cascade_fractions(&cp, c);
        if let Some(f) = c.distance {
            if !(f.is_finite() && f > camera.near && f <= camera.far) {
                self.err(
                    format!("{cp}.distance"),
                    format!(
                        "the shadow distance must lie beyond the camera's near plane ({}) and not beyond its far plane ({}), got {f}",
                        camera.near, camera.far
                    ),
                    "use a view depth in that range, or remove distance for the far plane",
                );
            }
        }
        if c.blend_of == BlendOf::Far && (0.0..=0.5).contains(&c.blend) {
            self.far_bands(&cp, c, camera);
        }
        if !(0.0..=0.5).contains(&c.blend) {
            self.err(
                format!("{cp}.blend"),
                format!(
                    "the blend band is a share of a cascade's range, at most half of it, got {}",
                    c.blend
                ),
                "use a value in [0, 0.5], e.g. 0.1",
            );
        }
    }

    /// A band of the far bound must stay within half its cascade's range (as a band of the
    /// range does), or the next cascade's fit would start before this one's.
    fn far_bands(&mut self, cp: &str, c: &Cascades, camera: &Camera) {
        let splits = crate::light::cascade_splits(c, camera.near, camera.far);
        for k in 0..splits.len().saturating_sub(2) {
            let (lo, hi) = (splits[k], splits[k + 1]);
            if c.blend * hi > 0.5 * (hi - lo) {
                self.err(
                    format!("{cp}.blend"),
                    format!(
                        "with blend_of \"far\", cascade {k}'s band ({} of its far bound {hi}) is more than half its range [{lo}, {hi}]",
                        c.blend
                    ),
                    format!(
                        "use a blend of at most {:.4}, or blend_of \"range\"",
                        0.5 * (hi - lo) / hi
                    ),
                );
                return;
            }
        }
    }

    /// `at`: with `fractions` only, `count − 1` increasing values in (0, 1).
    fn cascade_fractions(&mut self, cp: &str, c: &Cascades) {
        match (c.split, &c.at) {
            (SplitScheme::Fractions, None) => self.err(
                format!("{cp}.at"),
                "the fractions scheme needs its split fractions",
                format!(
                    "give at: {} increasing fractions in (0, 1), e.g. [0.1, 0.2, 0.5] for 4 cascades",
                    c.count.saturating_sub(1)
                ),
            ),
            (SplitScheme::Fractions, Some(at)) => {
                let inner = c.count.saturating_sub(1) as usize;
                let rising = at.windows(2).all(|w| w[0] < w[1]);
                if at.len() != inner || !rising || at.iter().any(|a| !(*a > 0.0 && *a < 1.0)) {
                    self.err(
                        format!("{cp}.at"),
                        format!(
                            "{} cascades need {inner} increasing fractions in (0, 1), got {at:?}",
                            c.count
                        ),
                        "list the inner splits as fractions of the range, e.g. [0.1, 0.2, 0.5]",
                    );
                }
            }
            (_, Some(_)) => self.err(
                format!("{cp}.at"),
                "split fractions belong to the fractions scheme only",
                "remove at, or use \"split\": \"fractions\"",
            ),
            (_, None) => {}
        }
    }

    fn shadow(&mut self, s: &Shadow) {
        for (k, n) in s.size.iter().enumerate() {
            if *n == 0 || *n > MAX_MAP_SIZE {
                self.err(
                    format!("shadow.size[{k}]"),
                    format!("map side must be from 1 to {MAX_MAP_SIZE} texels, got {n}"),
                    "use a size such as [1024, 1024]",
                );
            }
        }
        if let Filter::Pcf(n) = s.filter {
            if !(2..=MAX_PCF).contains(&n) {
                self.err(
                    "shadow.filter.pcf",
                    format!("kernel width must be from 2 to {MAX_PCF}, got {n}"),
                    "use 3 or 5 (1 is \"nearest\")",
                );
            }
        }
        if let Some(m) = s.mipmaps {
            self.mipmaps(s, m);
        }
        if let Some(f) = s.depth_func.filter(|f| !f.fits(s.depth_order)) {
            let (fits, order) = match s.depth_order {
                DepthOrder::Forward => ("\"less\" or \"less_equal\"", "forward"),
                DepthOrder::Reversed => ("\"greater\" or \"greater_equal\"", "reversed"),
            };
            self.err(
                "shadow.depth_func",
                format!(
                    "\"{}\" keeps the farther surface in {order} depth order (depth_order \"{order}\"), so the map would hold no caster's front",
                    f.name()
                ),
                format!("use {fits}, or change shadow.depth_order"),
            );
        }
        let b = &s.bias;
        self.finite("shadow.bias.constant", b.constant);
        self.finite("shadow.bias.polygon_offset[0]", b.polygon_offset[0]);
        self.finite("shadow.bias.polygon_offset[1]", b.polygon_offset[1]);
        if self.finite("shadow.bias.polygon_offset_clamp", b.polygon_offset_clamp)
            && b.polygon_offset_clamp < 0.0
        {
            self.err(
                "shadow.bias.polygon_offset_clamp",
                "must be ≥ 0 (0 means no clamp)",
                "give the largest offset as a positive depth distance",
            );
        }
        if let Some(sl) = b.slope {
            self.bias_distance("shadow.bias.slope.scale", sl.scale);
            self.bias_distance("shadow.bias.slope.max", sl.max);
        }
        if let Some(nl) = b.n_dot_l {
            self.bias_distance("shadow.bias.n_dot_l.scale", nl.scale);
            self.bias_distance("shadow.bias.n_dot_l.min", nl.min);
        }
        self.finite("shadow.bias.normal_offset", b.normal_offset);
    }

    /// `normal_offset_texels` and `light_offset` move the point by a directional light's
    /// texel and towards its one direction: a spot or point light has neither.
    fn light_bias(&mut self, c: &Case) {
        let b = &c.shadow.bias;
        for (field, x) in [
            ("normal_offset_texels", b.normal_offset_texels),
            ("light_offset", b.light_offset),
        ] {
            let path = format!("shadow.bias.{field}");
            if !self.finite(&path, x) || x == 0.0 {
                continue;
            }
            if c.lights.iter().any(|l| !matches!(l, Light::Directional(_))) {
                self.err(
                    path,
                    "only a directional light's map has one world size per texel and one direction to the light",
                    "use normal_offset (world units) and constant (depth units) with spot and point lights",
                );
            }
        }
        if c.shadow.filter.shader_taps() && c.lights.iter().any(|l| matches!(l, Light::Point(_))) {
            let name = if c.shadow.filter == Filter::Castano13 {
                "castano13"
            } else {
                "vogel5"
            };
            self.err(
                "shadow.filter",
                format!("{name} places its taps on a 2D map's texel grid; a point light's map is a cube"),
                "use \"linear\" or { \"pcf\": 3 } with point lights (Bevy and three.js filter cube maps another way)",
            );
        }
    }

    fn mipmaps(&mut self, s: &Shadow, m: Mipmaps) {
        let most = 32 - s.size[0].max(s.size[1]).max(1).leading_zeros();
        if !(2..=most).contains(&m.levels) {
            self.err(
                "shadow.mipmaps.levels",
                format!(
                    "a {:?} map has from 2 to {most} levels, got {}",
                    s.size, m.levels
                ),
                "give 2 or more levels, at most log2 of the larger side + 1",
            );
        }
        if !s.size.iter().all(|n| n.is_power_of_two()) {
            self.err(
                "shadow.size",
                format!("a mipmapped map needs power-of-two sides, got {:?}", s.size),
                "use sides such as [256, 256] or [512, 128]",
            );
        }
        if s.compare != Compare::Hardware {
            self.err(
                "shadow.compare",
                "mip levels are chosen by the sampler: a mipmapped map needs `hardware`",
                "set \"compare\": \"hardware\" or remove shadow.mipmaps",
            );
        }
        if matches!(s.filter, Filter::Pcf(_)) || s.filter.shader_taps() {
            self.err(
                "shadow.filter",
                "a mipmapped map is filtered by the sampler: `nearest` or `linear` within a level",
                "use \"nearest\" or \"linear\", or remove shadow.mipmaps",
            );
        }
    }

    fn shading(&mut self, s: &Shading) {
        self.unit_range("shading.ambient", s.ambient);
        self.unit_range("shading.dimming", s.dimming);
        self.unit_range("shading.specular", s.specular);
        self.unit_range("shading.shadowed_factor", s.shadowed_factor);
        if self.finite("shading.shininess", s.shininess) && s.shininess < 1.0 {
            self.err(
                "shading.shininess",
                format!("must be ≥ 1, got {}", s.shininess),
                "use 32",
            );
        }
    }
}

impl Extent {
    /// `(half_u, half_v)`.
    pub fn pair(self) -> (f32, f32) {
        match self {
            Extent::Square(h) => (h, h),
            Extent::Rect([u, v]) => (u, v),
        }
    }
}

impl Scale {
    /// Per-axis factors.
    pub fn vec(self) -> V3 {
        match self {
            Scale::Uniform(s) => [s; 3],
            Scale::PerAxis(v) => v,
        }
    }
}
