//! The camera of offscreen pictures: an orbit around the bounding sphere of what is drawn, and the
//! key light that follows it.

use glam::{Mat4, Vec3};

use super::gpu::FrameUniforms;
use super::{Style, View};

/// Where the camera looks from: the bounding sphere of what is drawn and a [`View`] around it.
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    pub centre: Vec3,
    pub radius: f32,
    pub view: View,
    pub aspect: f32,
}

/// The vertical field of view.
const FOV_DEG: f32 = 34.0;

impl Camera {
    /// Unit vector from the centre towards the eye (z is up).
    pub fn direction(&self) -> Vec3 {
        let (az, el) = (
            (self.view.azimuth_deg as f32).to_radians(),
            (self.view.elevation_deg as f32).to_radians(),
        );
        Vec3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin())
    }

    pub fn eye(&self) -> Vec3 {
        self.centre + self.direction() * self.radius * self.view.distance as f32
    }

    pub fn view_proj(&self) -> Mat4 {
        let eye = self.eye();
        // Looking straight down or up, z cannot be "up": use y then.
        let up = if self.direction().z.abs() > 0.999 {
            Vec3::Y
        } else {
            Vec3::Z
        };
        let distance = (eye - self.centre).length();
        let near = (distance - 1.5 * self.radius).max(1e-3 * distance);
        let far = distance + 1.5 * self.radius;
        Mat4::perspective_rh(FOV_DEG.to_radians(), self.aspect, near, far)
            * Mat4::look_at_rh(eye, self.centre, up)
    }

    /// The key light: above and to the left of the camera, towards the light.
    pub fn light(&self) -> Vec3 {
        let back = self.direction();
        let right = Vec3::Z.cross(back).try_normalize().unwrap_or(Vec3::X);
        let up = back.cross(right);
        (back + 0.8 * up - 0.5 * right).normalize()
    }

    pub fn uniforms(&self, style: Style, size: (u32, u32)) -> FrameUniforms {
        let wire = matches!(style, Style::Wireframe);
        FrameUniforms {
            view_proj: self.view_proj().to_cols_array_2d(),
            eye: self.eye().extend(1.0).to_array(),
            light: self.light().extend(0.0).to_array(),
            params: [f32::from(u8::from(wire)), 1.2, 0.22, 0.25],
            // Curves stay readable when printed: about 1/180 of the picture's height, at least 3 px.
            viewport: [
                size.0 as f32,
                size.1 as f32,
                (size.1 as f32 / 180.0).max(3.0),
                2e-4,
            ],
        }
    }
}

