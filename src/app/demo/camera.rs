//! The demo's camera controller: orbit around a target or fly freely, starting from (and
//! resetting to) the scene file's camera. Pure CPU state: the window feeds it input and
//! reads a [`Camera`] back each frame.
use std::collections::HashSet;

use glam::{Vec2, Vec3};
use winit::keyboard::KeyCode;

use crate::scene::Camera;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Left drag rotates around the target, right/middle drag pans it, the wheel zooms.
    Orbit,
    /// Left drag looks around, WASD moves, Q/E go down/up, Shift is faster, the wheel
    /// changes the speed.
    Fly,
}

impl Mode {
    pub fn name(self) -> &'static str {
        match self {
            Mode::Orbit => "orbit",
            Mode::Fly => "fly",
        }
    }
}

/// Which mouse drag is in progress.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Drag {
    Rotate,
    Pan,
}

pub struct CameraController {
    pub mode: Mode,
    start: Camera,
    /// Orthonormal frame around the scene's up vector: yaw turns about `up`, pitch tilts
    /// towards it.
    up: Vec3,
    ref_x: Vec3,
    ref_z: Vec3,
    yaw: f32,
    pitch: f32,
    /// Orbit: distance from the target to the eye; fly: how far ahead the target is kept.
    distance: f32,
    target: Vec3,
    position: Vec3,
    /// Fly speed in scene units per second.
    speed: f32,
    keys: HashSet<KeyCode>,
    drag: Option<Drag>,
    changed: bool,
    /// Nothing moved the camera since the start or the last reset: it is the scene file's
    /// camera exactly, not its round trip through yaw, pitch and distance (so that an
    /// untouched window renders what `prism render` does, bit for bit).
    at_start: bool,
}

const MAX_PITCH: f32 = 1.55;
/// Radians per pixel of mouse motion.
const ROTATE_PER_PIXEL: f32 = 0.005;

impl CameraController {
    pub fn new(start: Camera) -> Self {
        let mut c = CameraController {
            mode: Mode::Orbit,
            start,
            up: Vec3::Y,
            ref_x: Vec3::X,
            ref_z: Vec3::Z,
            yaw: 0.0,
            pitch: 0.0,
            distance: 1.0,
            target: Vec3::ZERO,
            position: Vec3::ZERO,
            speed: 1.0,
            keys: HashSet::new(),
            drag: None,
            changed: true,
            at_start: true,
        };
        c.reset();
        c
    }

    /// Back to the scene file's camera (the mode is kept).
    pub fn reset(&mut self) {
        let s = self.start;
        self.up = s.up.try_normalize().unwrap_or(Vec3::Y);
        // Any unit vector perpendicular to up serves as yaw 0.
        let helper = if self.up.x.abs() < 0.9 { Vec3::X } else { Vec3::Z };
        self.ref_x = (helper - self.up * helper.dot(self.up)).normalize();
        self.ref_z = self.ref_x.cross(self.up);
        let forward = (s.target - s.position).try_normalize().unwrap_or(-self.ref_z);
        self.pitch = forward.dot(self.up).clamp(-1.0, 1.0).asin().clamp(-MAX_PITCH, MAX_PITCH);
        self.yaw = forward.dot(self.ref_z).atan2(forward.dot(self.ref_x));
        self.distance = s.position.distance(s.target).max(1e-6);
        self.target = s.target;
        self.position = s.position;
        self.speed = self.distance * 0.5;
        self.changed = true;
        self.at_start = true;
    }

    /// The scene's size scale (the start camera's distance to its target), for steps of
    /// other controls (moving the light).
    pub fn scale(&self) -> f32 {
        self.start.position.distance(self.start.target).max(1e-6)
    }

    /// The horizontal frame (right, up, back) of the scene's camera, for moving lights.
    pub fn frame(&self) -> (Vec3, Vec3, Vec3) {
        (self.ref_x, self.up, self.ref_z)
    }

    fn forward(&self) -> Vec3 {
        let (s, c) = self.yaw.sin_cos();
        let horizontal = self.ref_x * c + self.ref_z * s;
        horizontal * self.pitch.cos() + self.up * self.pitch.sin()
    }

    pub fn toggle_mode(&mut self) {
        self.mode = match self.mode {
            Mode::Orbit => {
                self.position = self.target - self.forward() * self.distance;
                Mode::Fly
            }
            Mode::Fly => {
                self.target = self.position + self.forward() * self.distance;
                Mode::Orbit
            }
        };
        self.changed = true;
    }

    pub fn set_key(&mut self, key: KeyCode, pressed: bool) {
        if pressed {
            self.keys.insert(key);
        } else {
            self.keys.remove(&key);
        }
    }

    /// Forget held keys and drags (the window lost focus).
    pub fn release_all(&mut self) {
        self.keys.clear();
        self.drag = None;
    }

    pub fn set_drag(&mut self, drag: Option<Drag>) {
        self.drag = drag;
    }

    pub fn dragging(&self) -> bool {
        self.drag.is_some()
    }

    /// Mouse motion of `delta` pixels while a drag is in progress.
    pub fn mouse_moved(&mut self, delta: Vec2) {
        match self.drag {
            None => {}
            Some(Drag::Rotate) => {
                let sign = if self.mode == Mode::Orbit { -1.0 } else { 1.0 };
                self.yaw += sign * delta.x * ROTATE_PER_PIXEL;
                self.pitch = (self.pitch - sign * delta.y * ROTATE_PER_PIXEL).clamp(-MAX_PITCH, MAX_PITCH);
                self.changed = true;
                self.at_start = false;
            }
            Some(Drag::Pan) => {
                let forward = self.forward();
                let right = forward.cross(self.up).normalize_or_zero();
                let up = right.cross(forward);
                let step = self.distance * 0.002;
                let offset = (-right * delta.x + up * delta.y) * step;
                self.target += offset;
                self.position += offset;
                self.changed = true;
                self.at_start = false;
            }
        }
    }

    /// Mouse wheel of `lines` notches (positive: away from the user).
    pub fn wheel(&mut self, lines: f32) {
        let factor = 0.9f32.powf(lines);
        match self.mode {
            Mode::Orbit => {
                self.distance = (self.distance * factor).max(1e-6);
                self.at_start = false;
            }
            Mode::Fly => self.speed = (self.speed / factor).max(1e-6),
        }
        self.changed = true;
    }

    /// Advance by `dt` seconds of held keys. Returns whether the camera moved since the
    /// last call.
    pub fn update(&mut self, dt: f32) -> bool {
        if self.mode == Mode::Fly {
            let forward = self.forward();
            let right = forward.cross(self.up).normalize_or_zero();
            let mut dir = Vec3::ZERO;
            let held = |k| self.keys.contains(&k);
            if held(KeyCode::KeyW) {
                dir += forward;
            }
            if held(KeyCode::KeyS) {
                dir -= forward;
            }
            if held(KeyCode::KeyD) {
                dir += right;
            }
            if held(KeyCode::KeyA) {
                dir -= right;
            }
            if held(KeyCode::KeyE) {
                dir += self.up;
            }
            if held(KeyCode::KeyQ) {
                dir -= self.up;
            }
            if dir != Vec3::ZERO {
                let fast = held(KeyCode::ShiftLeft) || held(KeyCode::ShiftRight);
                let speed = if fast { self.speed * 4.0 } else { self.speed };
                self.position += dir.normalize() * speed * dt.min(0.25);
                self.changed = true;
                self.at_start = false;
            }
        }
        std::mem::take(&mut self.changed)
    }

    /// The camera to render with, `width` x `height` pixels.
    pub fn camera(&self, width: u32, height: u32) -> Camera {
        if self.at_start {
            return Camera { width, height, ..self.start };
        }
        let forward = self.forward();
        let (position, target) = match self.mode {
            Mode::Orbit => (self.target - forward * self.distance, self.target),
            Mode::Fly => (self.position, self.position + forward * self.distance),
        };
        Camera { position, target, up: self.up, vfov_deg: self.start.vfov_deg, width, height }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn start() -> Camera {
        Camera {
            position: Vec3::new(0.0, 1.0, 4.0),
            target: Vec3::new(0.0, 0.5, 0.0),
            up: Vec3::Y,
            vfov_deg: 40.0,
            width: 64,
            height: 48,
        }
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        a.distance(b) < 1e-4
    }

    #[test]
    fn starts_at_the_scene_camera_in_both_modes() {
        let mut c = CameraController::new(start());
        let cam = c.camera(64, 48);
        assert!(close(cam.position, start().position) && close(cam.target, start().target), "{cam:?}");
        c.toggle_mode();
        let cam = c.camera(64, 48);
        assert!(close(cam.position, start().position) && close(cam.target, start().target), "{cam:?}");
    }

    #[test]
    fn orbit_keeps_the_distance_and_reset_restores() {
        let mut c = CameraController::new(start());
        c.set_drag(Some(Drag::Rotate));
        c.mouse_moved(Vec2::new(120.0, -40.0));
        let cam = c.camera(64, 48);
        assert!(close(cam.target, start().target));
        let d0 = start().position.distance(start().target);
        assert!((cam.position.distance(cam.target) - d0).abs() < 1e-4);
        assert!(!close(cam.position, start().position));
        c.reset();
        assert!(close(c.camera(64, 48).position, start().position));
    }

    #[test]
    fn fly_moves_forward_with_w() {
        let mut c = CameraController::new(start());
        c.toggle_mode();
        c.update(0.0);
        c.set_key(KeyCode::KeyW, true);
        assert!(c.update(0.1));
        let cam = c.camera(64, 48);
        assert!(cam.position.distance(start().target) < start().position.distance(start().target));
        c.set_key(KeyCode::KeyW, false);
        assert!(!c.update(0.1));
    }
}
