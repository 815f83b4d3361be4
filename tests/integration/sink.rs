//! A render's `prepare` and `sink` failing: their errors come back whole, as
//! `RenderError::Sink`, for the caller to look at again.

use std::sync::atomic::AtomicBool;

use deepfield::io::IoError;
use deepfield::render::{self, Options, RenderError};

use crate::util::scene;

const SMALL: &str = "version = 1\n[view]\ncenter = [\"-0.75\", \"0.1\"]\nzoom = \"2\"\nwidth = 16\nheight = 16\n";

/// The error a failing sink returned, as its own type, with its cause beneath.
#[test]
fn a_sink_error_comes_back_whole() {
    let s = scene(SMALL);
    let plan = render::engine::plan(&s).expect("an engine");
    let full = || std::io::Error::new(std::io::ErrorKind::StorageFull, "no space left on device");
    let e = render::render(&s, &plan, Options::default(), &AtomicBool::new(false), &|_| {}, &|_| Ok(()), |_, ()| {
        Err(full().into())
    })
    .expect_err("the sink failed");
    assert!(!e.is_bad_input());
    let RenderError::Sink(inner) = &e else { panic!("not a sink error: {e}") };
    let io = inner.downcast_ref::<std::io::Error>().expect("the sink's own error");
    assert_eq!(io.kind(), std::io::ErrorKind::StorageFull);
    assert_eq!(e.to_string(), "no space left on device");
}

/// `prepare` failing on a worker stops the render with its error, as the sink's does.
#[test]
fn a_prepare_error_comes_back_whole() {
    let s = scene(SMALL);
    let dir = crate::util::scratch("sink-prepare");
    let missing = dir.join("no-such-folder").join("x.png");
    let plan = render::engine::plan(&s).expect("an engine");
    let e = render::render(
        &s,
        &plan,
        Options::default(),
        &AtomicBool::new(false),
        &|_| {},
        &|_| Ok(deepfield::io::write_png_rgb8(&missing, 1, 1, &[0; 3], "")?),
        |_, ()| Ok(()),
    )
    .expect_err("prepare failed");
    let RenderError::Sink(inner) = &e else { panic!("not a sink error: {e}") };
    let io = inner.downcast_ref::<IoError>().expect("the I/O layer's error");
    assert_eq!(io.kind(), Some(std::io::ErrorKind::NotFound));
    assert!(e.to_string().contains("does not exist"), "{e}");
}
