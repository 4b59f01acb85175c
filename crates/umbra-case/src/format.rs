//! The case format: the JSON a user writes, as serde types.
//!
//! Every struct denies unknown fields, so a misspelt key is an error rather than a silently
//! ignored default. Every optional field has its default in the doc comment and in
//! `cases/README.md`; the defaults live in the `default_*` functions at the bottom, one place.
//! Values here are what the user wrote: [`crate::validate`] checks them and [`crate::prepare`]
//! turns them into matrices. Nothing in this module computes anything.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// The name of the built-in twin (`umbra_case::twin`), which a case's own twins may not take.
pub const BIAS_ORDER: &str = "bias-order";

/// A 3-vector as written in JSON: `[x, y, z]`.
pub type V3 = [f32; 3];

/// One case: a scene, a camera, its lights and a shadow-mapping technique.
///
/// A case file writes one light as `light` and several as `lights` ([`CaseFile`], the file's
/// shape); a loaded case holds them all in `lights`, never empty, so that every consumer
/// goes over every light and none reads "the first" by accident.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "CaseFile", into = "CaseFile")]
pub struct Case {
    /// Identifier: lower-case letters, digits, `-` and `_`, beginning with a letter or a digit. Required.
    pub name: String,
    /// One sentence: what the case checks and why. Required.
    pub about: String,
    /// The objects. Required, at least one.
    pub scene: Scene,
    /// The viewer. Required.
    pub camera: Camera,
    /// Every light, 1 to [`MAX_LIGHTS`], never empty: each has its own map, placed by
    /// `shadow.placement`, and the lit pass adds their contributions (several: the `dimmed`
    /// model only).
    pub lights: Vec<Light>,
    /// The shadow-mapping technique.
    pub shadow: Shadow,
    /// The illumination model of docs/catalogue.md §17.
    pub shading: Shading,
    /// Parameters to sweep: JSON path to an axis.
    pub sweep: BTreeMap<String, SweepAxis>,
    /// What the judge may assume of this case.
    pub expect: Expect,
}

/// A case as its file writes it: what [`Case`] reads and writes. Its one difference is the
/// lights: `light` for one, `lights` for several (written back, a case of several lights
/// holds both, `light` equal to `lights[0]`, so that paths and conditions that name `light`
/// read the same document whatever the count).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaseFile {
    /// Identifier: lower-case letters, digits, `-` and `_`, beginning with a letter or a digit. Required.
    pub name: String,
    /// One sentence: what the case checks and why. Required.
    pub about: String,
    /// The objects. Required, at least one.
    pub scene: Scene,
    /// The viewer. Required.
    pub camera: Camera,
    /// The light: required, unless `lights` is given (then it may be left out, or must equal
    /// the first of them).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub light: Option<Light>,
    /// Several lights, each written as `light` is, 2 to [`MAX_LIGHTS`] (a case gives `light` for
    /// one, or `lights`). Default: none (the one `light`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub lights: Vec<Light>,
    /// The shadow-mapping technique. Default: every field's default.
    #[serde(default)]
    pub shadow: Shadow,
    /// The illumination model of docs/catalogue.md §17. Default: every field's default.
    #[serde(default)]
    pub shading: Shading,
    /// Parameters to sweep: JSON path (dots, as `light.directional.azimuth_deg`) to an axis.
    /// Several axes expand to their cartesian product. Default: none (one run).
    #[serde(default)]
    pub sweep: BTreeMap<String, SweepAxis>,
    /// What the judge may assume of this case. Default: every field's default.
    #[serde(default)]
    pub expect: Expect,
}

/// Why a [`CaseFile`] is not a [`Case`] (the loader names the field and the fix first:
/// `crate::point::parse_value`; this is what a plain serde reader sees).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum LightsError {
    /// Neither `light` nor `lights`.
    Missing,
    /// Both, and `light` is not `lights[0]`.
    Differ,
    /// `lights` with one light (one is written as `light`).
    One,
}

impl std::fmt::Display for LightsError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LightsError::Missing => f.write_str("missing field `light`"),
            LightsError::Differ => {
                f.write_str("both `light` and `lights` are given, and `light` is not `lights[0]`")
            }
            LightsError::One => write!(f, "1 lights; a case with `lights` has 2 to {MAX_LIGHTS}"),
        }
    }
}

impl TryFrom<CaseFile> for Case {
    type Error = LightsError;

    fn try_from(f: CaseFile) -> Result<Case, LightsError> {
        let lights = match (f.light, f.lights) {
            (None, lights) if lights.is_empty() => return Err(LightsError::Missing),
            (Some(one), lights) if lights.is_empty() => vec![one],
            (_, lights) if lights.len() == 1 => return Err(LightsError::One),
            (Some(one), lights) if one != lights[0] => return Err(LightsError::Differ),
            (_, lights) => lights,
        };
        Ok(Case {
            name: f.name,
            about: f.about,
            scene: f.scene,
            camera: f.camera,
            lights,
            shadow: f.shadow,
            shading: f.shading,
            sweep: f.sweep,
            expect: f.expect,
        })
    }
}

impl From<Case> for CaseFile {
    fn from(c: Case) -> CaseFile {
        let mut lights = c.lights;
        let light = (!lights.is_empty()).then(|| lights[0].clone());
        if lights.len() == 1 {
            lights.clear();
        }
        CaseFile {
            name: c.name,
            about: c.about,
            scene: c.scene,
            camera: c.camera,
            light,
            lights,
            shadow: c.shadow,
            shading: c.shading,
            sweep: c.sweep,
            expect: c.expect,
        }
    }
}

/// The objects of a scene. Every object casts and receives shadows.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// At least one object.
    pub objects: Vec<Object>,
    /// Moves the whole case (every object, the camera and the light) by this vector, as an
    /// application whose world sits far from the origin would: coordinates are offset in f64
    /// and rounded once to f32, so f32 spacing at the offset is what the renderers see.
    /// Default `[0, 0, 0]`.
    #[serde(default, skip_serializing_if = "is_zero3")]
    pub offset: V3,
}

fn is_zero3(v: &V3) -> bool {
    *v == [0.0; 3]
}

fn white() -> V3 {
    [1.0; 3]
}

fn is_white(v: &V3) -> bool {
    *v == [1.0; 3]
}

fn one() -> f32 {
    1.0
}

fn is_one(x: &f32) -> bool {
    *x == 1.0
}

fn is_false(b: &bool) -> bool {
    !*b
}

/// One primitive, written as `{ "box": { ... } }`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Object {
    /// A finite square (or rectangle) plane, lit on its normal side.
    Plane(Plane),
    /// An axis-aligned box before its transform.
    Box(BoxShape),
    /// A UV sphere.
    Sphere(Sphere),
    /// A capped cylinder along y with smooth side normals.
    Cylinder(Cylinder),
    /// An inline triangle mesh with flat normals.
    Mesh(Mesh),
}

/// `plane`: a rectangle through `point` with normal `normal`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Plane {
    /// A point of the plane, its centre. Required.
    pub point: V3,
    /// The lit side's normal (need not be unit length). Default `[0, 1, 0]`.
    #[serde(default = "default_up")]
    pub normal: V3,
    /// Half the side length, or `[half_u, half_v]` for a rectangle. Required.
    pub half_extent: Extent,
    /// Albedo, linear RGB in [0, 1]. Default `[0.8, 0.8, 0.8]`.
    #[serde(default = "default_albedo")]
    pub color: V3,
    /// Placement after the primitive is built. Default: identity.
    #[serde(default)]
    pub transform: Option<Transform>,
}

/// `box`: an axis-aligned box, then its transform.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxShape {
    /// Centre. Required.
    pub center: V3,
    /// Edge lengths along x, y, z. Required, each > 0.
    pub size: V3,
    /// Albedo. Default `[0.8, 0.8, 0.8]`.
    #[serde(default = "default_albedo")]
    pub color: V3,
    /// Placement after the primitive is built. Default: identity.
    #[serde(default)]
    pub transform: Option<Transform>,
}

/// `sphere`: a UV sphere with `segments` around and `segments / 2` from pole to pole.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sphere {
    /// Centre. Required.
    pub center: V3,
    /// Radius. Required, > 0.
    pub radius: f32,
    /// Segments around the equator. Default 32; 4 to 512.
    #[serde(default = "default_segments")]
    pub segments: u32,
    /// Albedo. Default `[0.8, 0.8, 0.8]`.
    #[serde(default = "default_albedo")]
    pub color: V3,
    /// Placement after the primitive is built. Default: identity.
    #[serde(default)]
    pub transform: Option<Transform>,
}

/// `cylinder`: a capped cylinder along y, centred at `center`, as engines tessellate one:
/// `segments` side quads whose vertex normals point straight out from the axis (so the
/// interpolated normal between them is short of unit length, by 1 − cos(π/segments) at a
/// quad's middle: 7.6 % at 8 segments), and flat caps.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Cylinder {
    /// Centre (the middle of the axis). Required.
    pub center: V3,
    /// Radius. Required, > 0.
    pub radius: f32,
    /// Length along y. Required, > 0.
    pub height: f32,
    /// Side quads around the axis. Default 16; 3 to 512.
    #[serde(default = "default_cylinder_segments")]
    pub segments: u32,
    /// Albedo. Default `[0.8, 0.8, 0.8]`.
    #[serde(default = "default_albedo")]
    pub color: V3,
    /// Placement after the primitive is built. Default: identity.
    #[serde(default)]
    pub transform: Option<Transform>,
}

/// `mesh`: triangles given inline; counter-clockwise seen from the front.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Mesh {
    /// Vertex positions. Required.
    pub positions: Vec<V3>,
    /// Triangles as vertex indices, counter-clockwise from the front. Required.
    pub triangles: Vec<[u32; 3]>,
    /// Albedo. Default `[0.8, 0.8, 0.8]`.
    #[serde(default = "default_albedo")]
    pub color: V3,
    /// Placement after the primitive is built. Default: identity.
    #[serde(default)]
    pub transform: Option<Transform>,
}

/// A half extent: one number for a square, two for a rectangle.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Extent {
    /// Square.
    Square(f32),
    /// Rectangle `[half_u, half_v]`.
    Rect([f32; 2]),
}

/// A uniform or per-axis scale.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Scale {
    /// The same factor on every axis.
    Uniform(f32),
    /// `[sx, sy, sz]`.
    PerAxis(V3),
}

/// Placement of a built primitive: `world = translate · rotate · scale · built`. The rotation
/// and the scale act about the world origin, so a primitive built at the origin turns in place.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Transform {
    /// Translation. Default `[0, 0, 0]`.
    #[serde(default)]
    pub translate: V3,
    /// Rotation about an axis through the origin. Default: none.
    #[serde(default)]
    pub rotate_deg: Option<Rotation>,
    /// Scale, each factor non-zero. Default 1.
    #[serde(default = "default_scale")]
    pub scale: Scale,
}

/// A rotation by `angle` degrees (right-handed) about `axis`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rotation {
    /// Axis, any non-zero length. Required.
    pub axis: V3,
    /// Angle in degrees. Required.
    pub angle: f32,
}

/// A perspective camera.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    /// Eye position. Required.
    pub eye: V3,
    /// Point looked at. Required, distinct from `eye`.
    pub target: V3,
    /// Up hint, not parallel to the view direction. Default `[0, 1, 0]`.
    #[serde(default = "default_up")]
    pub up: V3,
    /// Vertical field of view in degrees, in (0, 180). Default 45.
    #[serde(default = "default_fov")]
    pub fov_y_deg: f32,
    /// Near plane distance, > 0. Default 0.1.
    #[serde(default = "default_near")]
    pub near: f32,
    /// Far plane distance, > near. Default 100.
    #[serde(default = "default_far")]
    pub far: f32,
    /// Image size in pixels `[width, height]`, 1 to 8192 each. Default `[512, 512]`.
    #[serde(default = "default_camera_size")]
    pub size: [u32; 2],
    /// The colour the lit pass clears its colour target to (linear RGB, each channel in
    /// [0, 1], alpha 1): what every background pixel shows, judged like any other colour.
    /// Default `[0, 0, 0]`.
    #[serde(default, skip_serializing_if = "is_zero3")]
    pub clear: V3,
    /// Face culling in the lit pass: `none`, `back` or `front` (counter-clockwise seen from
    /// the eye is front, as in the shadow pass). Culled faces show what lies behind them; the
    /// exact truth's camera rays pass through them too. Default `none`.
    #[serde(default, skip_serializing_if = "Cull::is_none")]
    pub cull: Cull,
    /// The lit pass's colour target: `rgba8` (linear, 8-bit unsigned normalised) or
    /// `srgb8_alpha8` (GL_SRGB8_ALPHA8 with GL_FRAMEBUFFER_SRGB, Vulkan's
    /// R8G8B8A8_SRGB, wgpu's `Rgba8UnormSrgb`): the shaded linear colour, and the clear
    /// colour, are stored sRGB-encoded ([`crate::colour`]). Default `rgba8`.
    #[serde(default, skip_serializing_if = "ColorFormat::is_rgba8")]
    pub color_format: ColorFormat,
}

/// The lit pass's colour target format (`camera.color_format`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ColorFormat {
    /// RGBA8 unsigned normalised: the linear colour rounded to 8 bits.
    #[default]
    Rgba8,
    /// sRGB-encoded RGB, linear alpha, 8 bits each: the linear colour through the sRGB
    /// transfer function, then rounded.
    Srgb8Alpha8,
}

impl ColorFormat {
    /// `rgba8` (left out of a point's JSON).
    pub fn is_rgba8(&self) -> bool {
        *self == ColorFormat::Rgba8
    }
}

/// The one light, written as `{ "spot": { ... } }`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Light {
    /// A directional light with an orthographic shadow map.
    Directional(Directional),
    /// A spot light with a perspective shadow map.
    Spot(Spot),
    /// A point light with a six-face cube shadow map.
    Point(Point),
}

impl Light {
    /// How many map faces (layers) the light's shadow map has: six cube faces for a point
    /// light, one per cascade for a directional light, one for a spot light.
    pub fn map_faces(&self) -> u32 {
        match self {
            Light::Point(_) => 6,
            Light::Directional(d) => d.cascades.as_ref().map_or(1, |c| c.count),
            Light::Spot(_) => 1,
        }
    }

    /// The light's `color` and `intensity`, whatever its kind.
    pub fn emission(&self) -> (V3, f32) {
        match self {
            Light::Directional(d) => (d.color, d.intensity),
            Light::Spot(s) => (s.color, s.intensity),
            Light::Point(p) => (p.color, p.intensity),
        }
    }

    /// What the light multiplies the diffuse and specular terms by: `color · intensity`.
    pub fn radiance(&self) -> V3 {
        let (c, i) = self.emission();
        c.map(|x| x * i)
    }

    /// The light's field path in a case (`light.spot`), for errors.
    pub fn path(&self) -> &'static str {
        match self {
            Light::Directional(_) => "light.directional",
            Light::Spot(_) => "light.spot",
            Light::Point(_) => "light.point",
        }
    }
}

/// `directional`: placed either by `position` (as the write-ups do: the light's eye, looking at
/// `target`) or by `azimuth_deg` + `elevation_deg` (the direction *towards* the light:
/// `(cos e · sin a, sin e, cos e · cos a)`, azimuth from +z towards +x) and `distance`.
/// Bounds are either explicit (`ortho`) or fitted to the scene (`"fit": "scene"`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Directional {
    /// The light's eye. Give this or the two angles.
    #[serde(default)]
    pub position: Option<V3>,
    /// Azimuth of the direction towards the light, degrees.
    #[serde(default)]
    pub azimuth_deg: Option<f32>,
    /// Elevation of the direction towards the light above the x-z plane, degrees.
    #[serde(default)]
    pub elevation_deg: Option<f32>,
    /// Eye distance from `target` when placed by angles. Default 50.
    #[serde(default = "default_distance")]
    pub distance: f32,
    /// Point looked at. Default `[0, 0, 0]`.
    #[serde(default)]
    pub target: V3,
    /// Up hint of the light's view. Default `[0, 1, 0]`.
    #[serde(default = "default_up")]
    pub up: V3,
    /// Explicit orthographic bounds in the light's view space.
    #[serde(default)]
    pub ortho: Option<Ortho>,
    /// `"scene"`: fit the bounds to everything in the scene.
    #[serde(default)]
    pub fit: Option<Fit>,
    /// Cascaded shadow maps, in place of `ortho` and `fit`: the camera's view depths from its
    /// near to its far plane split into `count` slices, each with its own orthographic map
    /// fitted to the slice, the maps in the layers of one 2D array, a receiver looked up in the
    /// slice its view depth falls in.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cascades: Option<Cascades>,
    /// Light colour, linear RGB, each channel in [0, 1]: multiplies the diffuse and specular
    /// terms of the shading (the ambient term is the scene's, not the light's). Default
    /// `[1, 1, 1]`.
    #[serde(default = "white", skip_serializing_if = "is_white")]
    pub color: V3,
    /// Scales `color`, ≥ 0 (above 1 the lit colour saturates at the target's 1.0, as an
    /// engine's HDR light does on an 8-bit target without tone mapping). Default 1.
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub intensity: f32,
}

/// `cascades`: how a directional light's map is split along the camera's view depth.
///
/// Slice k of `count` ends at the view depth s_k = λ·n·(f/n)^(k/N) + (1 − λ)·(n + (f − n)·k/N)
/// (n the camera's near plane, f the shadow `distance`), the scheme of Zhang et al.'s
/// parallel-split shadow maps ("practical" in GPU Gems 3, ch. 10): λ = 0 is `uniform`, λ = 1
/// `logarithmic`; or, with `fractions`, at s_k = n + a_k·(f − n) for the fractions `at` (as
/// Unity's cascade splits and Godot's `split_1..3` give them). Each slice's map is fitted in x
/// and y to the light-view bounding box of the slice's eight corners (widened by 0.5 % a
/// side), and in depth to the whole scene so that every caster between a receiver and the
/// light is drawn; or, with `fit: stable`, as [`CascadeFit::Stable`] says.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Cascades {
    /// Slices (array layers), 1 to [`crate::validate::MAX_CASCADES`].
    pub count: u32,
    /// How the view depths are split. Default `practical`.
    #[serde(default)]
    pub split: SplitScheme,
    /// λ of the `practical` scheme, in [0, 1]. Default 0.5; only with `practical`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lambda: Option<f32>,
    /// The `fractions` scheme's inner splits: `count − 1` increasing fractions in (0, 1) of
    /// the range from the camera's near plane to `distance`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub at: Option<Vec<f32>>,
    /// The shadow distance: the view depth where the last cascade ends, beyond which
    /// receivers read lit (engines' "max shadow distance"). Default: the camera's far plane.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub distance: Option<f32>,
    /// The blend band: the share of each cascade's depth range, at its far end, over which its
    /// visibility fades linearly into the next cascade's (Unity's and Godot's blended splits).
    /// In [0, 0.5]; default 0 (a hard switch).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub blend: f32,
    /// What `blend` is a share of: `range` (default; the cascade's own depth range) or `far`
    /// (the cascade's far bound, Bevy's `overlap_proportion`: the band is the last
    /// `blend`·s_{k+1} of cascade k). With `far`, each band must stay within half its
    /// cascade's range.
    #[serde(default, skip_serializing_if = "BlendOf::is_range")]
    pub blend_of: BlendOf,
    /// How each cascade's map is fitted to its slice: `box` (default, above) or `stable`.
    #[serde(default, skip_serializing_if = "CascadeFit::is_box")]
    pub fit: CascadeFit,
}

/// What a cascade's blend band is a share of ([`Cascades::blend_of`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BlendOf {
    /// The cascade's depth range, s_{k+1} − s_k (Unity's, Godot's).
    #[default]
    Range,
    /// The cascade's far bound s_{k+1} (Bevy's `cascades_overlap_proportion`).
    Far,
}

impl BlendOf {
    fn is_range(&self) -> bool {
        *self == BlendOf::Range
    }
}

/// How a cascade's map is fitted to its slice ([`Cascades::fit`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CascadeFit {
    /// The light-view bounding box of the slice's corners in x and y (widened by 0.5 % a
    /// side), the whole scene in depth.
    #[default]
    Box,
    /// The "stable" fit (Valient, ShaderX6; Bevy's `calculate_cascade`): a square whose side
    /// is the longer of the slice's body and far-plane diagonals rounded up to a whole scene
    /// unit, so that it does not change as the camera turns; its centre floored to a whole
    /// texel of the light's view, so that it does not shimmer as the camera moves; in depth,
    /// only the slice's corners (casters nearer the light are clipped away unless
    /// `shadow.depth_clamp` pancakes them, as Bevy's `unclipped_depth` does).
    Stable,
}

impl CascadeFit {
    fn is_box(&self) -> bool {
        *self == CascadeFit::Box
    }
}

fn is_zero(x: &f32) -> bool {
    *x == 0.0
}

/// The split scheme of [`Cascades`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SplitScheme {
    /// Equal view-depth ranges (λ = 0).
    Uniform,
    /// Equal ratios of far to near (λ = 1): the optimum for perspective aliasing in Lloyd et
    /// al.'s analysis.
    Logarithmic,
    /// The blend of the two by `lambda`.
    #[default]
    Practical,
    /// Explicit fractions of the range (`at`).
    Fractions,
}

impl Cascades {
    /// λ as the split formula reads it.
    pub fn weight(&self) -> f32 {
        match self.split {
            SplitScheme::Uniform => 0.0,
            SplitScheme::Logarithmic => 1.0,
            SplitScheme::Practical => self.lambda.unwrap_or(0.5),
            SplitScheme::Fractions => 0.0,
        }
    }
}

/// Orthographic bounds, as `glOrtho` takes them.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ortho {
    /// Left, < right.
    pub left: f32,
    /// Right.
    pub right: f32,
    /// Bottom, < top.
    pub bottom: f32,
    /// Top.
    pub top: f32,
    /// Near plane distance (may be negative for an orthographic light), < far.
    pub near: f32,
    /// Far plane distance.
    pub far: f32,
}

/// What a fitted frustum encloses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Fit {
    /// Every object of the scene (casters and receivers).
    Scene,
}

/// `spot`: a perspective light at `position` looking at `target`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Spot {
    /// Light position. Required.
    pub position: V3,
    /// Point looked at. Required, distinct from `position`.
    pub target: V3,
    /// Up hint. Default `[0, 1, 0]`.
    #[serde(default = "default_up")]
    pub up: V3,
    /// Vertical field of view, degrees, in (0, 180). Required.
    pub fov_y_deg: f32,
    /// Near plane, > 0. Default 1.
    #[serde(default = "default_light_near")]
    pub near: f32,
    /// Far plane, > near. Default 100.
    #[serde(default = "default_far")]
    pub far: f32,
    /// Light colour, linear RGB, each channel in [0, 1]: multiplies the diffuse and specular
    /// terms of the shading (the ambient term is the scene's, not the light's). Default
    /// `[1, 1, 1]`.
    #[serde(default = "white", skip_serializing_if = "is_white")]
    pub color: V3,
    /// Scales `color`, ≥ 0 (above 1 the lit colour saturates at the target's 1.0, as an
    /// engine's HDR light does on an 8-bit target without tone mapping). Default 1.
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub intensity: f32,
}

/// `point`: an omnidirectional light with a cube shadow map (six 90° faces).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Point {
    /// Light position. Required.
    pub position: V3,
    /// Near plane, > 0. Default 0.1.
    #[serde(default = "default_near")]
    pub near: f32,
    /// Far plane, > near. Default 100.
    #[serde(default = "default_far")]
    pub far: f32,
    /// Light colour, linear RGB, each channel in [0, 1]: multiplies the diffuse and specular
    /// terms of the shading (the ambient term is the scene's, not the light's). Default
    /// `[1, 1, 1]`.
    #[serde(default = "white", skip_serializing_if = "is_white")]
    pub color: V3,
    /// Scales `color`, ≥ 0 (above 1 the lit colour saturates at the target's 1.0, as an
    /// engine's HDR light does on an 8-bit target without tone mapping). Default 1.
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub intensity: f32,
}

/// The shadow-mapping technique.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Shadow {
    /// Map size `[width, height]` in texels, 1 to 16384 each; square for point lights.
    /// Default `[1024, 1024]`.
    #[serde(default = "default_map_size")]
    pub size: [u32; 2],
    /// Depth format. Default `depth24`.
    #[serde(default)]
    pub format: DepthFormat,
    /// Lookup filter. Default `nearest`.
    #[serde(default)]
    pub filter: Filter,
    /// Who compares: the sampler (`hardware`) or the shader (`manual`). Default `hardware`.
    #[serde(default)]
    pub compare: Compare,
    /// Depth bias. Default: none at all.
    #[serde(default)]
    pub bias: Bias,
    /// Face culling in the shadow pass (the lit pass culls by `camera.cull`). Default `none`.
    #[serde(default)]
    pub cull: Cull,
    /// Depth clamp in the shadow pass (GL_DEPTH_CLAMP, Vulkan's depthClampEnable, wgpu's
    /// `unclipped_depth`): the light's near and far planes no longer clip, and each fragment's
    /// depth is clamped to [0, 1] after the polygon offset, so a caster between the light and
    /// its near plane is stored at the near plane ("pancaking") instead of being cut away.
    /// Default `false`.
    #[serde(default, skip_serializing_if = "is_false")]
    pub depth_clamp: bool,
    /// Where the [0,1] bias matrix is applied relative to the perspective divide.
    /// Default `before_divide`.
    #[serde(default)]
    pub bias_matrix: BiasMatrix,
    /// Framebuffer attachments of the shadow pass. Default `depth_only`.
    #[serde(default)]
    pub attachments: Attachments,
    /// What a lookup outside the map's [0,1]² footprint returns. Default `lit`.
    #[serde(default)]
    pub outside: Outside,
    /// What a receiver beyond the light's far plane reads. Default `compare`.
    #[serde(default, skip_serializing_if = "BeyondFar::is_compare")]
    pub beyond_far: BeyondFar,
    /// Skip the lookup (read lit) where the light-space w ≤ 0. Default `true`.
    #[serde(default = "default_true")]
    pub guard_behind_light: bool,
    /// Depth order: `forward` (clear 1, LEQUAL) or `reversed` (clear 0, GEQUAL). Default
    /// `forward`.
    #[serde(default)]
    pub depth_order: DepthOrder,
    /// The shadow pass's depth test: `less` or `less_equal` in forward order, `greater` or
    /// `greater_equal` in reversed order (GL's glDepthFunc, Vulkan's and wgpu's
    /// `depthCompareOp`). Default: the strict one of the order (`less`, `greater`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub depth_func: Option<DepthFunc>,
    /// Mip levels of the map, sampled with a mipmapped compare filter (see [`Mipmaps`]).
    /// Default: none (one level).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mipmaps: Option<Mipmaps>,
    /// Where several lights' maps live (`lights`): `separate` textures, one 2D `array` (spot
    /// and directional lights) or one `cube_array` (point lights). Default `separate`; read
    /// only with `lights`.
    #[serde(default, skip_serializing_if = "Placement::is_separate")]
    pub placement: Placement,
}

/// The most lights a case may have (`lights`).
pub const MAX_LIGHTS: usize = 4;

/// Where several lights' shadow maps live.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Placement {
    /// One texture per light, each bound to its own unit (the only way on GLES 2).
    #[default]
    Separate,
    /// One 2D array texture, light k's map in layer k, drawn into by layer and sampled with
    /// an array (compare) sampler at layer k (spot and directional lights).
    Array,
    /// One cube-map array texture, point light k's six faces in layer-faces 6k to 6k + 5,
    /// drawn into by layer-face and sampled with a cube-array (compare) sampler at cube k
    /// (ARB_texture_cube_map_array, GL 4.0, GLES 3.2; wgpu's CUBE_ARRAY_TEXTURES).
    CubeArray,
}

impl Placement {
    fn is_separate(&self) -> bool {
        *self == Placement::Separate
    }

    /// Name as a case writes it.
    pub fn name(self) -> &'static str {
        match self {
            Placement::Separate => "separate",
            Placement::Array => "array",
            Placement::CubeArray => "cube_array",
        }
    }
}

/// A mipmapped shadow map (docs/catalogue.md §12): level k is max(1, ⌊size / 2ᵏ⌋) texels a side,
/// and the sampler picks levels by the lookup's screen-space footprint (the LOD,
/// λ = log₂ ρ), so a receiver far from the camera reads coarse levels. Only for 2D maps
/// (spot and directional lights), the sampler's compare (`compare: hardware`), a `nearest`
/// or `linear` filter within a level, and power-of-two sizes.
///
/// Two ways to fill the levels differ in what they mean: `rendered` draws every level with
/// its own shadow pass at its own size, so each texel holds a real depth and the filter
/// averages *comparisons*; `averaged` stores in each level the mean of 2 × 2 depths of the
/// level above (what a generated mip chain holds; GL refuses `glGenerateMipmap` on a depth
/// format, so a program does it with a shader), and a mean depth lies on no surface: the
/// technique's error, shown against the truth.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Mipmaps {
    /// Levels including level 0, from 2 to log₂(the larger side) + 1. Required.
    pub levels: u32,
    /// Between levels: `nearest` (one level, GL's `*_MIPMAP_NEAREST`) or `linear` (the two
    /// nearest levels blended, `*_MIPMAP_LINEAR`). Default `nearest`.
    #[serde(default)]
    pub filter: MipFilter,
    /// How the levels below level 0 are filled: `rendered` or `averaged`. Default `rendered`.
    #[serde(default)]
    pub source: MipSource,
}

/// The filter between mip levels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MipFilter {
    /// The level nearest the LOD.
    #[default]
    Nearest,
    /// The two levels around the LOD, weighted by its fraction.
    Linear,
}

/// How a mip chain's lower levels are filled.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MipSource {
    /// Each level by its own shadow pass at its own size.
    #[default]
    Rendered,
    /// Each level the mean of 2 × 2 stored depths of the level above.
    Averaged,
}

impl Mipmaps {
    /// The size of level `k` of a map of `size`.
    pub fn level_size(size: [u32; 2], k: u32) -> [u32; 2] {
        size.map(|n| (n >> k).max(1))
    }
}

/// Depth texture formats.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DepthFormat {
    /// `DEPTH_COMPONENT` with no size: the driver picks; the reference stores it as 24 bits, and the
    /// judge lets its polygon-offset unit be a 24- or 32-bit one (GL 4.6 §8.5).
    Unsized,
    /// 16-bit unsigned normalised.
    Depth16,
    /// 24-bit unsigned normalised.
    #[default]
    Depth24,
    /// 32-bit float.
    Depth32f,
}

/// Lookup filters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Filter {
    /// One texel, floor(u · size).
    #[default]
    Nearest,
    /// 2x2 compare with bilinear weights (hardware PCF with a compare sampler).
    Linear,
    /// `{ "pcf": N }`: N x N NEAREST compares averaged in the shader, N in 2..=15.
    Pcf(u32),
    /// `"castano13"`: Castano's filter of The Witness as Bevy's default directional and spot
    /// filter (`ShadowFilteringMethod::Gaussian`) runs it, `sample_shadow_map_castano_thirteen`
    /// (nine samples: the name is for Castaño's 2013 article): nine LINEAR compares placed and
    /// weighted so that their sum, over 144, is a separable 6x6-texel tent (weights
    /// 4 − 3s, 7, 1 + 3s per axis). 2D maps only (Bevy filters cube maps otherwise).
    Castano13,
    /// `"vogel5"`: three.js's `PCFShadowMap` as r187's `shadowmap_pars_fragment` writes it
    /// for 2D maps: five LINEAR compares at `c.xy + vogelDiskSample(k, 5, φ) · radius`,
    /// averaged (× 0.2), with `radius` one texel along each axis (`shadow.radius` 1, its
    /// default, times r187's vec2 `texelSize`) and tap k at distance √((k + ½)/5) and angle
    /// k · 2.399963229728653 + φ. φ rotates the disk per pixel: 2π times the interleaved
    /// gradient noise fract(52.9829189 · fract(dot(window, (0.06711056, 0.00583715)))) of the
    /// pixel's window position (GL's gl_FragCoord.xy: pixel centres, y up from the frame's
    /// bottom row). 2D maps only (three.js filters point lights' cube maps otherwise).
    Vogel5,
}

impl Filter {
    /// Whether the sampler filters LINEAR where it compares (LINEAR itself, each of
    /// Castano's nine taps and each of the Vogel disk's five).
    pub fn sampler_linear(self) -> bool {
        matches!(self, Filter::Linear | Filter::Castano13 | Filter::Vogel5)
    }

    /// The shader places several LINEAR compares itself (Castano's, the Vogel disk's): the
    /// sampler filters each, the shader sums them.
    pub fn shader_taps(self) -> bool {
        matches!(self, Filter::Castano13 | Filter::Vogel5)
    }
}

/// Who does the depth comparison.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Compare {
    /// The sampler (`sampler2DShadow`, compare mode): the reference value is clamped to [0,1]
    /// for fixed-point formats.
    #[default]
    Hardware,
    /// The shader reads the depth and compares; nothing is clamped.
    Manual,
}

/// Depth bias, each field a distance *away from the light*; umbra applies the sign that the
/// depth order needs.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Bias {
    /// Subtracted from the light-space depth before the compare, in [0,1] depth units.
    /// Default 0.
    #[serde(default)]
    pub constant: f32,
    /// `[factor, units]` of `glPolygonOffset` in the shadow pass. Default `[0, 0]`.
    #[serde(default)]
    pub polygon_offset: [f32; 2],
    /// Largest polygon offset in depth units (Vulkan's depthBiasClamp); 0 = no clamp.
    /// Default 0.
    #[serde(default)]
    pub polygon_offset_clamp: f32,
    /// Shader slope bias: `min(scale · tan(acos(N·L)), max)` in depth units. Default: none.
    #[serde(default)]
    pub slope: Option<SlopeBias>,
    /// Shader bias linear in N·L: `max(scale · (1 − N·L), min)` in depth units, the form of
    /// LearnOpenGL's shadow-mapping chapter (scale 0.05, min 0.005) and the many programs
    /// copied from it. Default: none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub n_dot_l: Option<NdotLBias>,
    /// World-space distance the lookup point moves along the surface normal. Default 0.
    #[serde(default)]
    pub normal_offset: f32,
    /// A directional light's normal offset in texels of the map the point is looked up in:
    /// the point moves along the normal by this many times the world size of one texel of
    /// that map (of its cascade, for a cascaded light), after the cascade is chosen (Bevy's
    /// `shadow_normal_bias` × the cascade's `texel_size`). Default 0.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub normal_offset_texels: f32,
    /// A directional light's world-space distance the lookup point moves towards the light,
    /// after the cascade is chosen (Bevy's `shadow_depth_bias` along `direction_to_light`):
    /// in each map's depth units it is this distance over that map's depth range. Default 0.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub light_offset: f32,
}

/// Shader slope-scaled bias.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SlopeBias {
    /// Scale of tan(θ). Required, ≥ 0.
    pub scale: f32,
    /// Upper clamp. Required, ≥ 0.
    pub max: f32,
}

/// Shader bias `max(scale · (1 − N·L), min)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NdotLBias {
    /// Scale of 1 − N·L. Required, ≥ 0.
    pub scale: f32,
    /// The least bias. Required, ≥ 0.
    pub min: f32,
    /// Which light vector L is. Default `direction`.
    #[serde(default, skip_serializing_if = "LightVector::is_direction")]
    pub light: LightVector,
}

/// The light vector of an N·L bias.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LightVector {
    /// The unit vector towards the light the shading uses: the light's direction for a
    /// directional light, towards its position for a spot or point light.
    #[default]
    Direction,
    /// normalize(position − p) towards the light's eye even for a directional (orthographic)
    /// light, as tutorial code writes it (LearnOpenGL's `normalize(lightPos - fragPos)`); the
    /// same as `direction` for spot and point lights.
    Position,
}

impl LightVector {
    fn is_direction(&self) -> bool {
        *self == LightVector::Direction
    }
}

/// What a lookup whose receiver lies beyond the light's far plane reads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BeyondFar {
    /// Whatever the compare gives (a fixed-point format's hardware compare clamps the
    /// reference to the far plane and reads lit against a cleared texel; D32F and a manual
    /// compare read shadowed).
    #[default]
    Compare,
    /// The shader reads lit where the coordinate's depth lies beyond the far plane (> 1, or
    /// < 0 with reversed depth), before any shader bias: tutorial code's
    /// `if (projCoords.z > 1.0) shadow = 0.0`.
    Lit,
}

impl BeyondFar {
    fn is_compare(&self) -> bool {
        *self == BeyondFar::Compare
    }
}

/// Face culling.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Cull {
    /// Draw both faces.
    #[default]
    None,
    /// Cull back faces (counter-clockwise is front).
    Back,
    /// Cull front faces (moves acne to back faces).
    Front,
}

impl Cull {
    /// `none` (left out of a point's JSON).
    pub fn is_none(&self) -> bool {
        *self == Cull::None
    }

    /// The other face culled: what a pass whose front-face winding is wrong culls.
    pub fn flipped(self) -> Cull {
        match self {
            Cull::Back => Cull::Front,
            Cull::Front => Cull::Back,
            Cull::None => Cull::None,
        }
    }
}

/// Order of the bias matrix and the perspective divide.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BiasMatrix {
    /// `textureProj(B · P · V · x)`: the classic texture matrix, divide last.
    #[default]
    BeforeDivide,
    /// Divide by w first, then map NDC to [0,1].
    AfterDivide,
}

/// Shadow-pass attachments.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Attachments {
    /// Depth only; draw and read buffers NONE.
    #[default]
    DepthOnly,
    /// A dummy RGBA8 colour attachment beside depth (the "AMD needs colour" variant).
    WithColor,
}

/// Lookups whose (u, v) fall outside [0,1]².
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Outside {
    /// The shader tests the coordinates and reads lit.
    #[default]
    Lit,
    /// Clamp to border with the clear depth as border (compares as lit inside the range).
    Border,
    /// Clamp to the edge texel.
    ClampToEdge,
    /// Repeat (the classic mistake; shadows repeat).
    Repeat,
}

/// Depth order.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DepthOrder {
    /// Near → 0, far → 1; clear 1, compare LEQUAL.
    #[default]
    Forward,
    /// Near → 1, far → 0; clear 0, compare GEQUAL.
    Reversed,
}

/// The shadow pass's depth test (`shadow.depth_func`). The inclusive functions differ from
/// the strict ones only on a tie, where both keep the same depth: the stored map is the same
/// (GL 4.6 §17.3.4, Vulkan "Depth Comparison"). What a case with one tests is that the
/// driver honours the function it is given (a compare-op table with an entry swapped stores
/// the farthest surface instead of the nearest).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DepthFunc {
    /// GL_LESS: forward order's default.
    Less,
    /// GL_LEQUAL: what wgpu's shadow example and many engines use in forward order.
    LessEqual,
    /// GL_GREATER: reversed order's default.
    Greater,
    /// GL_GEQUAL.
    GreaterEqual,
}

impl DepthFunc {
    /// Whether a fragment whose depth equals the stored one passes.
    pub fn inclusive(self) -> bool {
        matches!(self, DepthFunc::LessEqual | DepthFunc::GreaterEqual)
    }

    /// Whether the function keeps the nearer fragment in `order`.
    pub fn fits(self, order: DepthOrder) -> bool {
        match order {
            DepthOrder::Forward => matches!(self, DepthFunc::Less | DepthFunc::LessEqual),
            DepthOrder::Reversed => matches!(self, DepthFunc::Greater | DepthFunc::GreaterEqual),
        }
    }

    /// The name the case format uses.
    pub fn name(self) -> &'static str {
        match self {
            DepthFunc::Less => "less",
            DepthFunc::LessEqual => "less_equal",
            DepthFunc::Greater => "greater",
            DepthFunc::GreaterEqual => "greater_equal",
        }
    }

    /// The function a shadow pass uses: `asked` (the case's `shadow.depth_func`) or the
    /// strict one of `order`.
    pub fn resolve(asked: Option<DepthFunc>, order: DepthOrder) -> DepthFunc {
        asked.unwrap_or(match order {
            DepthOrder::Forward => DepthFunc::Less,
            DepthOrder::Reversed => DepthFunc::Greater,
        })
    }

    /// The same function with its direction flipped (less_equal ↔ greater_equal, less ↔
    /// greater): what a compare-op table with the entry swapped applies.
    pub fn mirrored(self) -> DepthFunc {
        match self {
            DepthFunc::Less => DepthFunc::Greater,
            DepthFunc::LessEqual => DepthFunc::GreaterEqual,
            DepthFunc::Greater => DepthFunc::Less,
            DepthFunc::GreaterEqual => DepthFunc::LessEqual,
        }
    }
}

/// The illumination model (docs/catalogue.md §17); `shade` ∈ [0,1] is the shadow lookup.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Shading {
    /// `dimmed` or `classic`. Default `dimmed`.
    #[serde(default)]
    pub model: ShadingModel,
    /// Ambient term in [0,1]. Default 0.2.
    #[serde(default = "default_ambient")]
    pub ambient: f32,
    /// `dimmed`: share of diffuse kept in shadow, in [0,1]. Default 0.4.
    #[serde(default = "default_dimming")]
    pub dimming: f32,
    /// `dimmed`: specular strength in [0,1]. Default 0.25.
    #[serde(default = "default_specular")]
    pub specular: f32,
    /// `dimmed`: Blinn-Phong exponent, ≥ 1. Default 32.
    #[serde(default = "default_shininess")]
    pub shininess: f32,
    /// `classic`: colour factor in full shadow, in [0,1]. Default 0.5.
    #[serde(default = "default_shadowed_factor")]
    pub shadowed_factor: f32,
}

/// Which illumination model.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ShadingModel {
    /// `(ambient + (dimming + (1 - dimming)·shade)·diffuse)·albedo + shade·specular`.
    #[default]
    Dimmed,
    /// `(ambient + diffuse)·albedo · (shadowed_factor + (1 - shadowed_factor)·shade)`.
    Classic,
}

/// One sweep axis: `{ "from": a, "to": b, "steps": n }` (inclusive, optionally
/// `"scale": "log"`) or `{ "values": [...] }`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepAxis {
    /// First value.
    #[serde(default)]
    pub from: Option<f64>,
    /// Last value (inclusive).
    #[serde(default)]
    pub to: Option<f64>,
    /// Number of values, ≥ 1 (1 gives `from`).
    #[serde(default)]
    pub steps: Option<u32>,
    /// `linear` or `log` spacing. Default `linear`.
    #[serde(default)]
    pub scale: SweepScale,
    /// Explicit values (any JSON), instead of from/to/steps.
    #[serde(default)]
    pub values: Option<Vec<serde_json::Value>>,
}

/// Spacing of a from/to sweep.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SweepScale {
    /// Evenly spaced.
    #[default]
    Linear,
    /// Evenly spaced in log10; both ends > 0.
    Log,
}

/// What the judge may assume of a case.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Expect {
    /// Every backend's shadows agree with the reference within the spec's freedom.
    /// Default `true`.
    #[serde(default = "default_true")]
    pub backends_agree: bool,
    /// What the reference's error against the truth must be away from shadow edges.
    /// Default `reported`.
    #[serde(default)]
    pub interior_error: InteriorError,
    /// Metamorphic twins: variants of the case that every backend renders beside it and
    /// compares with it (see [`Twin`]). The `bias-order` twin (the other bias-matrix order,
    /// `legal`) is always added. Default: none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub twins: Vec<Twin>,
    /// A swept path along which the error against the truth (false shadow + false light, all
    /// judged pixels) must not rise, on every backend, in the order the sweep lists its
    /// values (other axes held fixed), e.g. `shadow.size` for growing maps. Default: none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error_falls_along: Option<String>,
}

impl Default for Expect {
    fn default() -> Self {
        Expect {
            backends_agree: true,
            interior_error: InteriorError::Reported,
            twins: Vec::new(),
            error_falls_along: None,
        }
    }
}

/// A metamorphic twin: the case with `set` applied (dotted paths, as in sweeps), rendered on
/// the same backend in the same run and compared with the case's own frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Twin {
    /// Identifier shown in reports: lower-case letters, digits, `-`, `_`, beginning with a letter or a digit. Required.
    pub name: String,
    /// Dotted JSON path to the value it takes in the twin. Required, at least one.
    pub set: BTreeMap<String, serde_json::Value>,
    /// How the twin must relate to the case. Default `legal`.
    #[serde(default)]
    pub agree: TwinAgree,
}

/// How a twin's frame must relate to its case's frame on the same backend.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TwinAgree {
    /// The same lit/shadowed answer at every pixel (a change the specs say cannot matter).
    Identical,
    /// Differences only where the reference's lookup allows them (ties, texel boundaries,
    /// filter freedom, truth edges, silhouettes): the same judge as backend vs reference.
    #[default]
    Legal,
    /// The twin's error against its own truth away from edges (false shadow + false light)
    /// is no larger than the case's: a change meant to improve accuracy.
    NoWorse,
    /// Differences and both errors are reported, never judged.
    Reported,
}

/// Claim on the error against the truth away from shadow edges.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InteriorError {
    /// Only reported (cases that show acne or leaks on purpose).
    #[default]
    Reported,
    /// Must be exactly zero: a well-biased case, where any interior error is a bug.
    Zero,
    /// No false light (no leak, no peter-panning); acne is only reported.
    NoFalseLight,
    /// No false shadow (no acne); leaks are only reported.
    NoFalseShadow,
}

impl Case {
    /// The case as light `k` alone lights it: only light `k`, and for every light but the
    /// first no ambient term (the first light's pass adds it once: the lit pass's
    /// contributions add up to the case's colour).
    pub fn for_light(&self, k: usize) -> Case {
        let mut c = self.clone();
        c.lights = vec![self.lights[k].clone()];
        if k > 0 {
            c.shading.ambient = 0.0;
        }
        c
    }

    /// Where light `k` is written in the case's file: `light` when it is the only one,
    /// `lights[k]` among several ([`CaseFile`]); errors about a light name this path.
    pub fn light_path(&self, k: usize) -> String {
        if self.lights.len() == 1 {
            "light".to_string()
        } else {
            format!("lights[{k}]")
        }
    }

    /// Whether the lights' maps are one array's layers: `shadow.placement` `array` or
    /// `cube_array` and a map for each of several lights to share it (a lone light's map is
    /// its own texture whatever the placement).
    pub fn maps_share_array(&self) -> bool {
        self.shadow.placement != Placement::Separate && self.lights.len() > 1
    }
}

impl Shadow {
    /// The shadow pass's depth test: `depth_func`, or the strict one of `depth_order`.
    pub fn depth_test(&self) -> DepthFunc {
        DepthFunc::resolve(self.depth_func, self.depth_order)
    }
}

impl Default for Shadow {
    fn default() -> Self {
        Shadow {
            size: default_map_size(),
            format: DepthFormat::default(),
            filter: Filter::default(),
            compare: Compare::default(),
            bias: Bias::default(),
            cull: Cull::default(),
            depth_clamp: false,
            bias_matrix: BiasMatrix::default(),
            attachments: Attachments::default(),
            outside: Outside::default(),
            beyond_far: BeyondFar::default(),
            guard_behind_light: true,
            depth_order: DepthOrder::default(),
            depth_func: None,
            mipmaps: None,
            placement: Placement::Separate,
        }
    }
}

impl Default for Shading {
    fn default() -> Self {
        Shading {
            model: ShadingModel::default(),
            ambient: default_ambient(),
            dimming: default_dimming(),
            specular: default_specular(),
            shininess: default_shininess(),
            shadowed_factor: default_shadowed_factor(),
        }
    }
}

fn default_up() -> V3 {
    [0.0, 1.0, 0.0]
}
fn default_albedo() -> V3 {
    [0.8, 0.8, 0.8]
}
fn default_segments() -> u32 {
    32
}
fn default_cylinder_segments() -> u32 {
    16
}
fn default_scale() -> Scale {
    Scale::Uniform(1.0)
}
fn default_fov() -> f32 {
    45.0
}
fn default_near() -> f32 {
    0.1
}
fn default_light_near() -> f32 {
    1.0
}
fn default_far() -> f32 {
    100.0
}
fn default_distance() -> f32 {
    50.0
}
fn default_camera_size() -> [u32; 2] {
    [512, 512]
}
fn default_map_size() -> [u32; 2] {
    [1024, 1024]
}
fn default_true() -> bool {
    true
}
fn default_ambient() -> f32 {
    0.2
}
fn default_dimming() -> f32 {
    0.4
}
fn default_specular() -> f32 {
    0.25
}
fn default_shininess() -> f32 {
    32.0
}
fn default_shadowed_factor() -> f32 {
    0.5
}
