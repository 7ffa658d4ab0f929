//! The camera of offscreen pictures: an orbit around the bounding sphere of what is drawn, and the
//! key light that follows it. The key light ([`key_light`]) and the uniforms ([`frame_uniforms`])
//! serve the editor's orbit camera too (`editor::camera`), so a picture and the viewport are lit
//! and shaded alike.

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

/// The vertical field of view (the editor's too).
pub const FOV_DEG: f32 = 34.0;

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
        key_light(self.direction(), Vec3::Z)
    }

    pub fn uniforms(&self, style: Style, size: (u32, u32)) -> FrameUniforms {
        frame_uniforms(
            self.view_proj(),
            self.eye(),
            self.light(),
            style,
            [size.0 as f32, size.1 as f32],
            // Curves stay readable when printed: about 1/180 of the picture's height, at least 3 px.
            (size.1 as f32 / 180.0).max(3.0),
        )
    }
}

/// The key light (towards the light): above and to the left of a camera that looks along `-back`
/// (`back`: the unit vector from what is seen towards the eye), with `up` the world's up as the
/// camera holds it.
pub fn key_light(back: Vec3, up: Vec3) -> Vec3 {
    let right = up.cross(back).try_normalize().unwrap_or(Vec3::X);
    let up = back.cross(right);
    (back + 0.8 * up - 0.5 * right).normalize()
}

/// The per-frame uniforms (`shaders/frame.wgsl`) of every pipeline: the camera, the key
/// light, the style's shading parameters, and the viewport's size and curve width in pixels.
pub fn frame_uniforms(
    view_proj: Mat4,
    eye: Vec3,
    light: Vec3,
    style: Style,
    viewport: [f32; 2],
    curve_width: f32,
) -> FrameUniforms {
    let wire = matches!(style, Style::Wireframe);
    FrameUniforms {
        view_proj: view_proj.to_cols_array_2d(),
        eye: eye.extend(1.0).to_array(),
        light: light.extend(0.0).to_array(),
        params: [f32::from(u8::from(wire)), 1.2, 0.22, 0.25],
        viewport: [viewport[0], viewport[1], curve_width, 2e-4],
    }
}
