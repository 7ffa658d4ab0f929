//! The viewport's camera: an orbit about a target point, in f64 so that a pick ray and a drag plane
//! are exact to rounding, and the same matrices (rounded to f32) for the GPU.
//!
//! Pixels: (0, 0) is the top left corner of the viewport, x to the right, y down, in physical pixels
//! (egui points times pixels per point); a pixel's centre is at +0.5.

use embedding::{Point3, Vector3};
use glam::{DMat4, DVec2, DVec3, DVec4};

use crate::render::camera::{frame_uniforms, key_light};
use crate::render::gpu::FrameUniforms;
use crate::render::{Style, View};

/// The vertical field of view, as `ntori render` uses.
pub const FOV_DEG: f64 = crate::render::camera::FOV_DEG as f64;
/// The default view: the same azimuth, elevation and distance (in bounding radii) as `ntori render`.
pub const DEFAULT_AZIMUTH: f64 = View::DEFAULT.azimuth_deg;
pub const DEFAULT_ELEVATION: f64 = View::DEFAULT.elevation_deg;
pub const DEFAULT_DISTANCE: f64 = View::DEFAULT.distance;

/// A ray from the eye: origin and unit direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Point3,
    pub direction: Vector3,
}

impl Ray {
    pub fn at(&self, t: f64) -> Point3 {
        self.origin + self.direction * t
    }
}

/// A pixel's width at `depth` on the view axis, in a viewport `height` pixels high.
fn pixel_at_centre(depth: f64, height: f64) -> f64 {
    2.0 * depth * (FOV_DEG.to_radians() / 2.0).tan() / height.max(1.0)
}

/// An orbit camera: it looks at `target` from `distance` away, from the direction given by azimuth
/// (about the vertical z axis) and elevation (above the horizontal plane), both in degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbitCamera {
    pub target: DVec3,
    pub azimuth: f64,
    pub elevation: f64,
    pub distance: f64,
    /// The bounding sphere of what is drawn (for the near and far planes and for framing).
    pub scene_centre: DVec3,
    pub scene_radius: f64,
}

impl OrbitCamera {
    /// The default view of a bounding sphere.
    pub fn new(centre: Point3, radius: f64) -> OrbitCamera {
        let radius = radius.max(1e-9);
        OrbitCamera {
            target: to_glam(centre),
            azimuth: DEFAULT_AZIMUTH,
            elevation: DEFAULT_ELEVATION,
            distance: DEFAULT_DISTANCE * radius,
            scene_centre: to_glam(centre),
            scene_radius: radius,
        }
    }

    /// Back to the default view of the current bounding sphere.
    pub fn reset(&mut self) {
        *self = OrbitCamera::new(to_point(self.scene_centre), self.scene_radius);
    }

    /// Keeps the direction, centres the bounding sphere and moves back until it fills the view.
    pub fn frame(&mut self, aspect: f64) {
        self.target = self.scene_centre;
        let half = (FOV_DEG.to_radians() / 2.0).tan();
        // The sphere fits both the vertical and the horizontal field of view, with a margin.
        let fit = half * aspect.clamp(1e-3, 1.0);
        self.distance = 1.1 * self.scene_radius / fit.atan().sin();
    }

    /// A new bounding sphere (the model changed) without moving the camera.
    pub fn set_scene(&mut self, centre: Point3, radius: f64) {
        self.scene_centre = to_glam(centre);
        self.scene_radius = radius.max(1e-9);
    }

    /// Unit vector from the target towards the eye (z is up).
    pub fn direction(&self) -> DVec3 {
        let (az, el) = (self.azimuth.to_radians(), self.elevation.to_radians());
        DVec3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin())
    }

    pub fn eye(&self) -> DVec3 {
        self.target + self.direction() * self.distance
    }

    fn up(&self) -> DVec3 {
        // Looking straight down or up, z cannot be "up": use y then.
        if self.direction().z.abs() > 0.999 {
            DVec3::Y
        } else {
            DVec3::Z
        }
    }

    /// The camera's right and up vectors in world space (unit, orthogonal to the view direction).
    pub fn basis(&self) -> (DVec3, DVec3) {
        let back = self.direction();
        let right = self.up().cross(back).normalize_or(DVec3::X);
        (right, back.cross(right))
    }

    /// Near and far planes: around the scene's bounding sphere as seen from the eye.
    fn clip_planes(&self) -> (f64, f64) {
        let d = (self.eye() - self.scene_centre).length();
        let far = d + 1.5 * self.scene_radius;
        let near = (d - 1.5 * self.scene_radius).max(1e-3 * far);
        (near, far)
    }

    pub fn view(&self) -> DMat4 {
        DMat4::look_at_rh(self.eye(), self.target, self.up())
    }

    pub fn projection(&self, aspect: f64) -> DMat4 {
        let (near, far) = self.clip_planes();
        DMat4::perspective_rh(FOV_DEG.to_radians(), aspect, near, far)
    }

    pub fn view_proj(&self, size: [f64; 2]) -> DMat4 {
        self.projection(size[0] / size[1]) * self.view()
    }

    /// The ray through a pixel position of a viewport of `size` pixels.
    pub fn ray(&self, pixel: [f64; 2], size: [f64; 2]) -> Ray {
        let inverse = self.view_proj(size).inverse();
        let ndc = DVec2::new(
            2.0 * pixel[0] / size[0] - 1.0,
            1.0 - 2.0 * pixel[1] / size[1],
        );
        let unproject = |z: f64| {
            let p = inverse * DVec4::new(ndc.x, ndc.y, z, 1.0);
            p.truncate() / p.w
        };
        let origin = self.eye();
        // Through the eye (exact) and the far point, so that every pick ray starts at the same place.
        let direction = (unproject(1.0) - origin).normalize();
        Ray {
            origin: to_point(origin),
            direction: to_vector(direction),
        }
    }

    /// Where a point appears: its pixel position, and its depth along the view direction (negative
    /// behind the eye).
    pub fn project(&self, point: Point3, size: [f64; 2]) -> ([f64; 2], f64) {
        let p = self.view_proj(size) * to_glam(point).extend(1.0);
        let depth = (to_glam(point) - self.eye()).dot(-self.direction());
        let ndc = p.truncate() / p.w;
        (
            [(ndc.x + 1.0) / 2.0 * size[0], (1.0 - ndc.y) / 2.0 * size[1]],
            depth,
        )
    }

    /// Where the ray through `pixel` meets the plane through `anchor` facing the camera: the point a
    /// drag that started at `anchor` should reach.
    pub fn on_view_plane(&self, pixel: [f64; 2], size: [f64; 2], anchor: Point3) -> Point3 {
        let ray = self.ray(pixel, size);
        let normal = to_vector(self.direction());
        let denominator = ray.direction.dot(&normal);
        if denominator.abs() < 1e-12 {
            return anchor;
        }
        ray.at((anchor - ray.origin).dot(&normal) / denominator)
    }

    /// Turns the view by pixel deltas (a full viewport height is half a turn).
    pub fn orbit(&mut self, delta: [f64; 2], height: f64) {
        let per_pixel = 180.0 / height.max(1.0);
        self.azimuth = (self.azimuth - delta[0] * per_pixel).rem_euclid(360.0);
        self.elevation = (self.elevation + delta[1] * per_pixel).clamp(-89.9, 89.9);
    }

    /// Moves the target so that what was under the cursor stays under it.
    pub fn pan(&mut self, delta: [f64; 2], height: f64) {
        let (right, up) = self.basis();
        let world_per_pixel = pixel_at_centre(self.distance, height);
        self.target += (-right * delta[0] + up * delta[1]) * world_per_pixel;
    }

    /// The shortest motion at `depth` (along the view direction) that can move a point by a
    /// whole pixel anywhere in a viewport of `size` pixels: a pixel's width at the centre, over
    /// √(1 + t²) for the tangent t of the angle between the view direction and the viewport's
    /// corner (off the axis, motion along the ray moves the image too).
    pub fn pixel_at(&self, depth: f64, size: [f64; 2]) -> f64 {
        let half = (FOV_DEG.to_radians() / 2.0).tan();
        let aspect = size[0] / size[1].max(1.0);
        let corner = half * (1.0 + aspect * aspect).sqrt();
        pixel_at_centre(depth.max(0.0), size[1]) / (1.0 + corner * corner).sqrt()
    }

    /// The least depth along the view direction among `points` (negative: behind the eye).
    pub fn nearest_depth(&self, points: &[Point3]) -> f64 {
        let (eye, forward) = (self.eye(), -self.direction());
        points
            .iter()
            .map(|&p| (to_glam(p) - eye).dot(forward))
            .fold(f64::INFINITY, f64::min)
    }

    /// Zooms by a factor (> 1: closer), within a range about the scene's size.
    pub fn zoom(&mut self, factor: f64) {
        if factor.is_finite() && factor > 0.0 {
            self.distance =
                (self.distance / factor).clamp(0.05 * self.scene_radius, 200.0 * self.scene_radius);
        }
    }

    /// The GPU's uniforms for a viewport of `size` pixels: the matrices in f64 rounded to f32, the
    /// key light and the shading as offscreen pictures have them.
    pub fn uniforms(&self, style: Style, size: [u32; 2]) -> FrameUniforms {
        let size_f = [f64::from(size[0].max(1)), f64::from(size[1].max(1))];
        frame_uniforms(
            self.view_proj(size_f).as_mat4(),
            self.eye().as_vec3(),
            key_light(self.direction().as_vec3(), self.up().as_vec3()),
            style,
            [size_f[0] as f32, size_f[1] as f32],
            3.0,
        )
    }
}

/// A position in glam's terms (the camera's maths is glam's; the surface's is nalgebra's).
pub fn to_glam(p: Point3) -> DVec3 {
    DVec3::new(p.x, p.y, p.z)
}

/// A glam position as a surface-space position.
pub fn to_point(v: DVec3) -> Point3 {
    Point3::new(v.x, v.y, v.z)
}

/// A glam direction as a surface-space vector.
pub fn to_vector(v: DVec3) -> Vector3 {
    Vector3::new(v.x, v.y, v.z)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_projected_point_lies_on_its_pixel_ray() {
        let mut camera = OrbitCamera::new(Point3::new(0.5, -0.2, 0.1), 2.0);
        camera.orbit([37.0, -12.0], 600.0);
        camera.pan([5.0, 9.0], 600.0);
        let size = [800.0, 600.0];
        let point = Point3::new(0.9, 0.3, -0.4);
        let (pixel, depth) = camera.project(point, size);
        assert!(depth > 0.0);
        let ray = camera.ray(pixel, size);
        let t = (point - ray.origin).dot(&ray.direction);
        assert!((ray.at(t) - point).norm() < 1e-12);
        let on_plane = camera.on_view_plane(pixel, size, point);
        assert!((on_plane - point).norm() < 1e-12);
    }
}
