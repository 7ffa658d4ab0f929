//! The 3D view: pointer and wheel input turned into camera moves, picks, pins and drags on
//! [`EditorState`] (at once, as the pointer moves), the GPU picture ([`ViewportRenderer`]) shown as
//! an egui texture, and the overlays drawn over it (control net, pins, the drag, the hovered and the
//! picked point, the curvature legend).

use std::time::Duration;

use egui::{Align2, Color32, FontId, PointerButton, Pos2, Rect, Sense, Stroke, Vec2};
use embedding::Point3;

use super::camera::to_glam;
use super::gpu::{BACKGROUND, ViewportRenderer};
use super::panels::{Level, Messages};
use super::state::{EditorError, EditorState, Grab, PIN_RADIUS_PX, Pick};
use crate::render::{CurvatureKind, Image, Style};

/// What a pointer drag in the viewport does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Interaction {
    None,
    Orbit,
    Pan,
    Edit,
}

/// The viewport: its GPU side, the pointer's interaction and what it picked.
pub struct Viewport {
    render_state: Option<egui_wgpu::RenderState>,
    gpu: Option<ViewportRenderer>,
    /// The egui texture showing the picture, and the picture's generation it was made for.
    texture: Option<(egui::TextureId, u64)>,
    /// What was last drawn (uniforms, size), to skip drawing an unchanged view.
    last_drawn: Option<(Vec<u8>, [u32; 2])>,
    interaction: Interaction,
    hover: Option<Pick>,
    selected: Option<Pick>,
    rect: Rect,
    /// The modifiers held when the primary button last went down: a click or drag is read with
    /// them, so a quick Ctrl + click (Ctrl up again within the frame) still pins.
    press_modifiers: egui::Modifiers,
}

impl Viewport {
    pub fn new(render_state: Option<egui_wgpu::RenderState>) -> Viewport {
        Viewport {
            render_state,
            gpu: None,
            texture: None,
            last_drawn: None,
            interaction: Interaction::None,
            press_modifiers: egui::Modifiers::NONE,
            hover: None,
            selected: None,
            rect: Rect::from_min_size(Pos2::ZERO, Vec2::new(800.0, 600.0)),
        }
    }

    /// A new model: nothing hovered, picked or dragged.
    pub fn reset(&mut self) {
        self.hover = None;
        self.selected = None;
        self.interaction = Interaction::None;
    }

    /// The drag in progress ended (cancelled).
    pub fn end_interaction(&mut self) {
        self.interaction = Interaction::None;
    }

    /// The viewport's rectangle in egui points (as of the last frame).
    pub fn rect(&self) -> Rect {
        self.rect
    }

    /// The surface point under the pointer (as of the last frame).
    pub fn hover(&self) -> Option<&Pick> {
        self.hover.as_ref()
    }

    /// The last clicked surface point.
    pub fn selected(&self) -> Option<&Pick> {
        self.selected.as_ref()
    }

    /// The last picture, read back from the GPU.
    pub fn screenshot(&self) -> Result<Image, EditorError> {
        let (Some(gpu), Some(rs)) = (&self.gpu, &self.render_state) else {
            return Err(EditorError::Other("no GPU viewport".into()));
        };
        Ok(gpu.read_back(&rs.device, &rs.queue)?)
    }

    /// The viewport in the rest of `ui`: input, picture, overlays. `job` names the background job
    /// that runs, if one does.
    pub fn ui(
        &mut self,
        ui: &mut egui::Ui,
        frame: &eframe::Frame,
        state: Option<&mut EditorState>,
        job: Option<&str>,
        messages: &mut Messages,
    ) {
        let rect = ui.available_rect_before_wrap();
        let response = ui.allocate_rect(rect, Sense::click_and_drag());
        self.rect = rect;
        let ctx = ui.ctx().clone();
        let ppp = ctx.pixels_per_point();
        let size_px = [
            (rect.width() * ppp).round().max(1.0) as u32,
            (rect.height() * ppp).round().max(1.0) as u32,
        ];
        let painter = ui.painter_at(rect);
        let Some(state) = state else {
            painter.rect_filled(rect, 0.0, background());
            let text = job.map_or("No model".to_owned(), |j| format!("{}…", capitalise(j)));
            painter.text(
                rect.center(),
                Align2::CENTER_CENTER,
                text,
                FontId::proportional(18.0),
                Color32::LIGHT_GRAY,
            );
            ctx.request_repaint_after(Duration::from_millis(100));
            return;
        };
        state.viewport = [f64::from(size_px[0]), f64::from(size_px[1])];
        let map = PixelMap { rect, size_px };
        self.input(&ctx, &response, state, map, messages);
        self.picture(frame, &painter, state, map);
        self.overlays(&painter, state, map, job);
        if self.interaction != Interaction::None {
            ctx.request_repaint();
        }
    }

    fn input(
        &mut self,
        ctx: &egui::Context,
        response: &egui::Response,
        state: &mut EditorState,
        map: PixelMap,
        messages: &mut Messages,
    ) {
        let ppp = ctx.pixels_per_point();
        if let Some(m) = ctx.input(|i| primary_press_modifiers(&i.events)) {
            self.press_modifiers = m;
        }
        let modifiers = self.press_modifiers;
        if response.drag_started() {
            let origin = ctx
                .input(|i| i.pointer.press_origin())
                .unwrap_or(map.rect.center());
            self.interaction = if response.drag_started_by(PointerButton::Secondary)
                || response.drag_started_by(PointerButton::Middle)
                || (response.drag_started_by(PointerButton::Primary) && modifiers.shift)
            {
                Interaction::Pan
            } else if !response.drag_started_by(PointerButton::Primary) || modifiers.alt {
                Interaction::Orbit
            } else {
                match state.press(map.to_pixel(origin)) {
                    Ok(Some(_)) => Interaction::Edit,
                    Ok(None) => Interaction::Orbit,
                    Err(e) => {
                        messages.push(format!("cannot drag: {e}"), Level::Error);
                        Interaction::Orbit
                    }
                }
            };
            self.hover = None;
        }
        if response.dragged() {
            let delta = response.drag_delta() * ppp;
            let (dx, dy) = (f64::from(delta.x), f64::from(delta.y));
            let height = state.viewport[1];
            match self.interaction {
                Interaction::Orbit => state.camera.orbit([dx, dy], height),
                Interaction::Pan => state.camera.pan([dx, dy], height),
                Interaction::Edit => {
                    if let Some(pos) = response.interact_pointer_pos()
                        && let Err(e) = state.drag_to(map.to_pixel(pos))
                    {
                        messages.push(format!("drag: {e}"), Level::Error);
                    }
                }
                Interaction::None => {}
            }
        }
        if response.drag_stopped() {
            if self.interaction == Interaction::Edit {
                state.release();
            }
            self.interaction = Interaction::None;
        }
        if response.clicked()
            && let Some(pos) = response.interact_pointer_pos()
        {
            let pixel = map.to_pixel(pos);
            if modifiers.command {
                state.toggle_pin(pixel);
            } else {
                self.selected = state.pick(pixel);
            }
        }
        if response.double_clicked()
            && let Some(pick) = &self.selected
        {
            state.camera.target = to_glam(pick.surface);
        }
        if response.hovered() {
            let (wheels, zoom) = ctx.input(|i| (wheel_gestures(&i.events), i.zoom_delta()));
            let height = state.viewport[1];
            let ppp = f64::from(ppp);
            for gesture in wheels {
                match gesture {
                    Wheel::Zoom(factor) => state.camera.zoom(factor),
                    Wheel::Orbit(d) => state.camera.orbit([-d[0] * ppp, -d[1] * ppp], height),
                    Wheel::Pan(d) => state.camera.pan([d[0] * ppp, d[1] * ppp], height),
                }
            }
            if zoom != 1.0 {
                state.camera.zoom(f64::from(zoom));
            }
        }
        if self.interaction == Interaction::None || state.stroke().is_some() {
            self.hover = response
                .hover_pos()
                .and_then(|p| state.pick(map.to_pixel(p)));
        }
        let cursor = match self.interaction {
            Interaction::Edit => Some(egui::CursorIcon::Grabbing),
            Interaction::Orbit | Interaction::Pan => Some(egui::CursorIcon::Move),
            Interaction::None if response.hovered() => {
                let on_pin = response
                    .hover_pos()
                    .is_some_and(|p| state.pin_near(map.to_pixel(p), PIN_RADIUS_PX).is_some());
                (on_pin || self.hover.is_some()).then_some(egui::CursorIcon::Grab)
            }
            Interaction::None => None,
        };
        if let Some(icon) = cursor {
            ctx.set_cursor_icon(icon);
        }
    }

    /// The 3D picture: the mesh and the drag brought up to date on the GPU, drawn when anything it
    /// shows changed, and shown as a texture.
    fn picture(
        &mut self,
        frame: &eframe::Frame,
        painter: &egui::Painter,
        state: &mut EditorState,
        map: PixelMap,
    ) {
        let PixelMap { rect, size_px } = map;
        let Some(rs) = frame.wgpu_render_state() else {
            painter.rect_filled(rect, 0.0, background());
            painter.text(
                rect.center(),
                Align2::CENTER_CENTER,
                "No GPU: the viewport needs wgpu (install a Vulkan driver, e.g. mesa-vulkan-drivers)",
                FontId::proportional(15.0),
                Color32::LIGHT_GRAY,
            );
            return;
        };
        let gpu = self
            .gpu
            .get_or_insert_with(|| ViewportRenderer::new(&rs.device));
        let changed =
            match state.with_display(|mesh, drag| gpu.sync(&rs.device, &rs.queue, mesh, drag)) {
                Ok(changed) => changed,
                Err(e) => {
                    // A mesh too large for this GPU: say so where the picture would be.
                    painter.rect_filled(rect, 0.0, background());
                    painter.text(
                        rect.center(),
                        Align2::CENTER_CENTER,
                        format!("Cannot draw this mesh: {e}"),
                        FontId::proportional(15.0),
                        Color32::LIGHT_GRAY,
                    );
                    return;
                }
            };
        let uniforms = state.camera.uniforms(state.style(), size_px);
        let key = (bytemuck::bytes_of(&uniforms).to_vec(), size_px);
        if changed || self.last_drawn.as_ref() != Some(&key) || gpu.texture_view().is_none() {
            gpu.render(&rs.device, &rs.queue, size_px, &uniforms);
            self.last_drawn = Some(key);
        }
        let generation = gpu.generation;
        let Some(view) = gpu.texture_view() else {
            unreachable!("rendered above")
        };
        let mut renderer = rs.renderer.write();
        let id = match self.texture {
            Some((id, g)) if g == generation => id,
            Some((id, _)) => {
                renderer.update_egui_texture_from_wgpu_texture(
                    &rs.device,
                    view,
                    wgpu::FilterMode::Linear,
                    id,
                );
                id
            }
            None => renderer.register_native_texture(&rs.device, view, wgpu::FilterMode::Linear),
        };
        self.texture = Some((id, generation));
        painter.image(
            id,
            rect,
            Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0)),
            Color32::WHITE,
        );
    }

    fn overlays(
        &self,
        painter: &egui::Painter,
        state: &EditorState,
        map: PixelMap,
        job: Option<&str>,
    ) {
        let rect = map.rect;
        let project = |p: Point3| {
            let (q, depth) = state.camera.project(p, state.viewport);
            (depth > 0.0).then(|| map.to_pos(q))
        };
        if let Some(chart) = state.control_chart {
            control_net(painter, state, chart, &project);
        }
        let dragging = state
            .drag()
            .map(|d| (d.plan.start_position, d.plan.point, d.grab));
        for (i, &pin) in state.pins().iter().enumerate() {
            if matches!(dragging, Some((_, _, Grab::Pin(k))) if k == i) {
                continue;
            }
            if let Some(p) = project(state.surface_point(pin)) {
                painter.circle(
                    p,
                    5.0,
                    Color32::from_rgb(220, 50, 50),
                    Stroke::new(1.5, Color32::WHITE),
                );
            }
        }
        let yellow = Color32::from_rgb(250, 210, 60);
        if let Some((start, point, _)) = dragging {
            let now = state.surface_point(point);
            if let (Some(a), Some(b)) = (project(start), project(now)) {
                painter.line_segment([a, b], Stroke::new(1.0, yellow));
                painter.circle(b, 5.0, yellow, Stroke::new(1.5, Color32::BLACK));
            }
        } else if let Some(pick) = &self.hover
            && let Some(p) = project(pick.surface)
        {
            painter.circle_stroke(p, 4.0, Stroke::new(1.5, yellow));
        }
        // The brush's radius, drawn on the surface's tangent plane under the cursor (or at the
        // dragged point).
        let brush_at = match dragging {
            Some((_, point, Grab::Surface)) => Some(point),
            Some(_) => None,
            None => self.hover.as_ref().map(|h| h.point),
        };
        if state.influence > 0.0
            && let Some(point) = brush_at
        {
            let jet = state.layout().eval(state.control(), point);
            let ring = brush_ring(jet.pos, jet.normal(), state.radius());
            let points: Vec<Pos2> = ring.into_iter().filter_map(project).collect();
            if points.len() == BRUSH_RING_POINTS {
                painter.add(egui::Shape::closed_line(
                    points,
                    Stroke::new(1.5, Color32::from_rgba_unmultiplied(250, 210, 60, 200)),
                ));
            }
        }
        if let Some(pick) = &self.selected
            && let Some(p) = project(state.surface_point(pick.point))
        {
            painter.circle_stroke(p, 6.0, Stroke::new(1.5, Color32::WHITE));
        }
        if let (Style::Curvature(kind), Some(range)) =
            (state.style(), state.mesh().curvature_range())
        {
            curvature_legend(painter, rect, kind, range);
        }
        if let Some(job) = job {
            painter.text(
                rect.left_top() + Vec2::new(12.0, 12.0),
                Align2::LEFT_TOP,
                format!("{}…", capitalise(job)),
                FontId::proportional(15.0),
                Color32::LIGHT_GRAY,
            );
        }
        if let Some(pick) = &self.hover {
            painter.text(
                rect.left_bottom() + Vec2::new(8.0, -8.0),
                Align2::LEFT_BOTTOM,
                state.describe(pick),
                FontId::monospace(12.0),
                Color32::from_gray(220),
            );
        }
    }
}

/// Points on the drawn brush circle.
const BRUSH_RING_POINTS: usize = 64;

/// A circle of `radius` about `centre` in the plane normal to `normal`.
fn brush_ring(centre: Point3, normal: embedding::Vector3, radius: f64) -> Vec<Point3> {
    let helper = if normal.x.abs() < 0.9 {
        embedding::Vector3::x()
    } else {
        embedding::Vector3::y()
    };
    let a = normal.cross(&helper).normalize();
    let b = normal.cross(&a);
    (0..BRUSH_RING_POINTS)
        .map(|k| {
            let t = std::f64::consts::TAU * k as f64 / BRUSH_RING_POINTS as f64;
            centre + (a * t.cos() + b * t.sin()) * radius
        })
        .collect()
}

/// Between egui positions (points) and viewport pixels (physical, from the top left corner).
#[derive(Clone, Copy)]
struct PixelMap {
    rect: Rect,
    size_px: [u32; 2],
}

impl PixelMap {
    fn to_pixel(self, p: Pos2) -> [f64; 2] {
        let (rect, [w, h]) = (self.rect, self.size_px.map(f64::from));
        [
            f64::from(p.x - rect.min.x) * w / f64::from(rect.width()),
            f64::from(p.y - rect.min.y) * h / f64::from(rect.height()),
        ]
    }

    fn to_pos(self, q: [f64; 2]) -> Pos2 {
        let (rect, [w, h]) = (self.rect, self.size_px.map(f64::from));
        Pos2::new(
            rect.min.x + (q[0] * f64::from(rect.width()) / w) as f32,
            rect.min.y + (q[1] * f64::from(rect.height()) / h) as f32,
        )
    }
}

/// One chart's control net: its grid lines and points, in the chart's colour.
fn control_net(
    painter: &egui::Painter,
    state: &EditorState,
    chart: charts::ChartId,
    project: &dyn Fn(Point3) -> Option<Pos2>,
) {
    let g = state.layout().grid(chart);
    let net = state.control_net(chart);
    let colour = {
        let c = state
            .atlas()
            .charts()
            .get(chart.index())
            .map_or([0.8; 3], |k| crate::render::palette::stroke_rgb(k.kind()));
        Color32::from_rgb(
            (c[0] * 255.0) as u8,
            (c[1] * 255.0) as u8,
            (c[2] * 255.0) as u8,
        )
    };
    let points: Vec<Option<Pos2>> = net.iter().map(|&p| project(p)).collect();
    let stroke = Stroke::new(1.0, colour.gamma_multiply(0.8));
    for j in 0..g {
        for i in 0..g {
            let k = j * g + i;
            let Some(a) = points[k] else { continue };
            if i + 1 < g
                && let Some(b) = points[k + 1]
            {
                painter.line_segment([a, b], stroke);
            }
            if j + 1 < g
                && let Some(b) = points[k + g]
            {
                painter.line_segment([a, b], stroke);
            }
        }
    }
    for p in points.into_iter().flatten() {
        painter.circle_filled(p, 2.5, colour);
    }
}

/// What a wheel or trackpad event does in the viewport.
enum Wheel {
    Zoom(f64),
    Orbit([f64; 2]),
    Pan([f64; 2]),
}

/// A mouse wheel zooms; two fingers on a trackpad orbit (with Shift: pan); pinching, or the wheel
/// with Ctrl, zooms through egui's zoom delta (left out here).
/// The modifiers of this frame's last press of the primary button, if any.
fn primary_press_modifiers(events: &[egui::Event]) -> Option<egui::Modifiers> {
    events.iter().rev().find_map(|e| match e {
        egui::Event::PointerButton {
            button: PointerButton::Primary,
            pressed: true,
            modifiers,
            ..
        } => Some(*modifiers),
        _ => None,
    })
}

fn wheel_gestures(events: &[egui::Event]) -> Vec<Wheel> {
    use egui::{MouseWheelSource, MouseWheelUnit};
    events
        .iter()
        .filter_map(|e| match e {
            egui::Event::MouseWheel {
                unit,
                delta,
                source,
                modifiers,
                ..
            } if !modifiers.command && !modifiers.ctrl => {
                let (dx, dy) = (f64::from(delta.x), f64::from(delta.y));
                let fingers = matches!(
                    source,
                    MouseWheelSource::Trackpad | MouseWheelSource::Momentum
                ) || (*source == MouseWheelSource::Unknown
                    && *unit == MouseWheelUnit::Point);
                Some(if fingers && modifiers.shift {
                    Wheel::Pan([dx, dy])
                } else if fingers {
                    Wheel::Orbit([dx, dy])
                } else {
                    let steps = match unit {
                        MouseWheelUnit::Point => dy / 50.0,
                        MouseWheelUnit::Line => dy,
                        MouseWheelUnit::Page => 4.0 * dy,
                    };
                    Wheel::Zoom(1.15f64.powf(steps))
                })
            }
            _ => None,
        })
        .collect()
}

/// The curvature style's colour scale, at the viewport's right edge.
fn curvature_legend(painter: &egui::Painter, rect: Rect, kind: CurvatureKind, range: f64) {
    let bar = Rect::from_min_size(
        Pos2::new(rect.right() - 70.0, rect.bottom() - 210.0),
        Vec2::new(14.0, 160.0),
    );
    const STEPS: usize = 40;
    let step = bar.height() / STEPS as f32;
    for i in 0..STEPS {
        let t = 1.0 - 2.0 * (i as f64 + 0.5) / STEPS as f64;
        let [r, g, b] = crate::render::scene::diverging(t).map(|x| (x * 255.0).round() as u8);
        painter.rect_filled(
            Rect::from_min_size(
                bar.min + Vec2::new(0.0, i as f32 * step),
                Vec2::new(bar.width(), step + 0.5),
            ),
            0.0,
            Color32::from_rgb(r, g, b),
        );
    }
    let font = FontId::proportional(12.0);
    let text = Color32::from_gray(225);
    let title = match kind {
        CurvatureKind::Gaussian => "K",
        CurvatureKind::Mean => "H",
    };
    painter.text(
        bar.center_top() - Vec2::new(0.0, 6.0),
        Align2::CENTER_BOTTOM,
        title,
        font.clone(),
        text,
    );
    for (y, value) in [
        (bar.top(), range),
        (bar.center().y, 0.0),
        (bar.bottom(), -range),
    ] {
        painter.text(
            Pos2::new(bar.right() + 5.0, y),
            Align2::LEFT_CENTER,
            format!("{value:+.3}"),
            font.clone(),
            text,
        );
    }
}

fn background() -> Color32 {
    let [r, g, b] = BACKGROUND.map(|x| (x * 255.0) as u8);
    Color32::from_rgb(r, g, b)
}

fn capitalise(s: &str) -> String {
    let mut c = s.chars();
    c.next().map_or(String::new(), |f| {
        f.to_uppercase().collect::<String>() + c.as_str()
    })
}
