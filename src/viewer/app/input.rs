//! Keyboard input and Newton zooming: the keys that navigate, and the search for the
//! minibrot or Misiurewicz point under the pointer, run off the UI thread.

use super::*;

/// Newton zooming in progress and its settings.
#[derive(Default)]
pub(super) struct NewtonState {
    /// The search running on its own thread.
    pending: Option<std::sync::mpsc::Receiver<Result<(Nav, String), String>>>,
    /// Zoom by this factor towards what is found (1 or less: frame it).
    factor: f64,
    /// What the last search found (or why it found nothing).
    note: Option<String>,
}

impl NewtonState {
    /// The zoom factor towards what is found, for its control.
    pub(super) fn factor_mut(&mut self) -> &mut f64 {
        &mut self.factor
    }

    /// What the last search found, or why it found nothing.
    pub(super) fn note(&self) -> Option<&str> {
        self.note.as_deref()
    }

    /// True while a search runs.
    pub(super) fn pending(&self) -> bool {
        self.pending.is_some()
    }
}

impl ViewerApp {
    /// Starts a Newton zoom search from pixel `at` (from the image centre, y down).
    pub(super) fn start_newton(&mut self, target: crate::viewer::newton::Target, at: [f64; 2]) {
        if !self.doc.is_mandelbrot() || !self.doc.formula().is_quadratic() {
            self.newton.note = Some("Newton zoom searches the Mandelbrot set's parameter plane (z² + c)".into());
            return;
        }
        let (tx, rx) = std::sync::mpsc::channel();
        let (nav, h, factor) = (self.view.nav().clone(), self.view.height(), self.newton.factor);
        std::thread::spawn(move || {
            let _ = tx.send(crate::viewer::newton::newton_zoom(&nav, at, h, target, factor));
        });
        self.newton.pending = Some(rx);
        self.newton.note = None;
    }

    /// Goes to the view a finished Newton search found.
    pub(super) fn poll_newton(&mut self, ctx: &egui::Context) {
        let Some(rx) = &self.newton.pending else { return };
        match rx.try_recv() {
            Ok(result) => {
                self.newton.pending = None;
                match result {
                    Ok((nav, line)) => {
                        self.newton.note = Some(line);
                        self.go(nav);
                    }
                    Err(e) => self.newton.note = Some(e),
                }
            }
            Err(std::sync::mpsc::TryRecvError::Empty) => {
                ctx.request_repaint_after(std::time::Duration::from_millis(50))
            }
            Err(std::sync::mpsc::TryRecvError::Disconnected) => self.newton.pending = None,
        }
    }

    /// Newton zooming is being searched.
    pub fn newton_pending(&self) -> bool {
        self.newton.pending()
    }

    /// What the last Newton zoom found, or why it found nothing.
    pub fn newton_note(&self) -> Option<&str> {
        self.newton.note()
    }

    pub(super) fn keys(&mut self, ctx: &egui::Context) {
        if ctx.egui_wants_keyboard_input() {
            return;
        }
        let (newton_minibrot, newton_point, pointer) =
            ctx.input(|i| (i.key_pressed(Key::N), i.key_pressed(Key::M), i.pointer.hover_pos()));
        if newton_minibrot || newton_point {
            let ppp = ctx.pixels_per_point();
            let r = self.view.image_rect();
            let at = pointer
                .filter(|p| r.contains(*p))
                .map_or([0.0, 0.0], |p| [((p.x - r.center().x) * ppp) as f64, ((p.y - r.center().y) * ppp) as f64]);
            let target = if newton_minibrot {
                crate::viewer::newton::Target::Minibrot
            } else {
                crate::viewer::newton::Target::Misiurewicz
            };
            self.start_newton(target, at);
        }
        let h = self.view.height();
        let step = h * 0.1;
        let (left, right, up, down, plus, minus, home, back) = ctx.input(|i| {
            (
                i.key_pressed(Key::ArrowLeft),
                i.key_pressed(Key::ArrowRight),
                i.key_pressed(Key::ArrowUp),
                i.key_pressed(Key::ArrowDown),
                i.key_pressed(Key::Plus) || i.key_pressed(Key::Equals),
                i.key_pressed(Key::Minus),
                i.key_pressed(Key::Home),
                i.key_pressed(Key::Backspace),
            )
        });
        let pans = [(left, -step, 0.0), (right, step, 0.0), (up, 0.0, -step), (down, 0.0, step)];
        for (pressed, dx, dy) in pans {
            if pressed {
                let n = self.view.nav().pan(dx, dy, h);
                self.go(n);
            }
        }
        if plus {
            let n = self.view.nav().zoom_about(2.0, [0.0, 0.0], h);
            self.go(n);
        }
        if minus {
            let n = self.view.nav().zoom_about(0.5, [0.0, 0.0], h);
            self.go(n);
        }
        if home {
            self.go(self.default_view());
        }
        if back {
            self.back();
        }
    }
}
