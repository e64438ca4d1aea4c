//! The camera's keys: a field of view on any axis, a thin lens (depth of
//! field), a near clipping plane and the orthographic projection, from the
//! scene file to the image.

mod common;

use caustic::accel::AccelKind;
use caustic::film::Film;
use caustic::scene::LoadedScene;
use caustic::scene::{parse_scene, FovAxis, Projection, SceneError};
use std::path::Path;

fn load(text: &str) -> Result<LoadedScene, SceneError> {
    parse_scene(text, Path::new("camera.toml"))
}

/// A checkerboard wall at z = 0 seen from z = 5, a small grey ball at
/// z = 4.5 in front of the lens; `camera` adds keys to `[camera]`.
fn scene(camera: &str) -> String {
    format!(
        "[render]\nwidth = 64\nheight = 64\nspp = 16\nintegrator = \"path\"\nseed = 2\n\
         [camera]\nposition = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\nvfov = 30\n{camera}\n\
         [materials.wall]\ndiffuse = {{ type = \"checkerboard\", colour0 = 0.9, colour1 = 0.05, scale = 8.0 }}\n\
         [materials.grey]\ndiffuse = 0.5\n\
         [[lights]]\ntype = \"environment\"\ncolour = [1.0, 1.0, 1.0]\n\
         [[objects]]\ntype = \"quad\"\ncorner = [-2.0, -2.0, 0.0]\nu = [4.0, 0.0, 0.0]\nv = [0.0, 4.0, 0.0]\nmaterial = \"wall\"\n\
         [[objects]]\ntype = \"sphere\"\ncenter = [0.1, 0.1, 4.0]\nradius = 0.05\nmaterial = \"grey\"\n"
    )
}

fn image(text: &str) -> Film {
    let scene = load(text).unwrap();
    common::render::film(&scene, AccelKind::KdTree)
}

/// Mean absolute difference between horizontal neighbours: high for a sharp
/// checkerboard, low for a blurred one.
fn sharpness(film: &Film) -> f32 {
    let mut sum = 0.0;
    for y in 0..film.height {
        for x in 1..film.width {
            sum += (film.get(x, y).x - film.get(x - 1, y).x).abs();
        }
    }
    sum / (film.height * (film.width - 1)) as f32
}

#[test]
fn camera_keys_are_read_and_checked() {
    let s = load(
        &scene("fov = 50\nfov_axis = \"diagonal\"\naperture_radius = 0.3\nfocus_distance = 3.0\nnear_clip = 0.25")
            .replace("vfov = 30\n", ""),
    )
    .unwrap();
    let c = &s.scene.camera;
    assert_eq!((c.fov_deg, c.fov_axis), (50.0, FovAxis::Diagonal));
    assert_eq!((c.aperture_radius, c.focus_distance, c.near_clip), (0.3, 3.0, 0.25));
    // By default: a pinhole focused on `look_at`, no clipping.
    let c = load(&scene("")).unwrap().scene.camera;
    assert_eq!(
        (c.fov_axis, c.aperture_radius, c.focus_distance, c.near_clip),
        (FovAxis::Y, 0.0, 5.0, 0.0)
    );
    let error = |keys: &str| load(&scene(keys)).unwrap_err().to_string();
    let e = error("fov = 40");
    assert!(
        e.contains("camera.toml:11:7") && e.contains("give the field of view once"),
        "{e}"
    );
    let e = error("fov_axis = \"x\"");
    assert!(e.contains("`fov_axis` goes with `fov`"), "{e}");
    let e = load(&scene("fov = 40\nfov_axis = \"width\"").replace("vfov = 30\n", ""))
        .unwrap_err()
        .to_string();
    assert!(e.contains("unknown `fov_axis` `width`"), "{e}");
    assert!(error("aperture_radius = -1").contains("`aperture_radius` = -1 must be ≥ 0"));
    assert!(error("focus_distance = 0").contains("`focus_distance` = 0 must be > 0"));
    assert!(error("near_clip = -0.5").contains("`near_clip` = -0.5 must be ≥ 0"));
}

#[test]
fn a_horizontal_field_of_view_matches_its_vertical_equivalent() {
    // 64 × 64: x and y spans are the same, so `fov_axis = "x"` renders the same image.
    let vertical = image(&scene(""));
    let horizontal = image(&scene("fov = 30\nfov_axis = \"x\"").replace("vfov = 30\n", ""));
    assert!(vertical.pixels == horizontal.pixels, "the images differ");
}

#[test]
fn the_thin_lens_blurs_what_is_out_of_focus() {
    let pinhole = image(&scene(""));
    // Focused on the wall: as sharp as the pinhole (within noise).
    let focused = image(&scene("aperture_radius = 0.3\nfocus_distance = 5.0"));
    // Focused 2 units in front of the wall: blurred.
    let blurred = image(&scene("aperture_radius = 0.3\nfocus_distance = 3.0"));
    let (p, f, b) = (sharpness(&pinhole), sharpness(&focused), sharpness(&blurred));
    assert!(f > 0.85 * p, "focused {f} against pinhole {p}");
    assert!(b < 0.6 * p, "blurred {b} against pinhole {p}");
    // The mean is the same: defocus moves light, it does not lose it.
    let mean = |f: &Film| f.pixels.iter().map(|c| c.x).sum::<f32>() / f.pixels.len() as f32;
    assert!((mean(&blurred) / mean(&pinhole) - 1.0).abs() < 0.03);
    // A zero aperture is the pinhole, bit for bit.
    assert!(image(&scene("aperture_radius = 0.0\nfocus_distance = 3.0")).pixels == pinhole.pixels);
}

#[test]
fn the_near_clip_hides_what_is_closer() {
    // The ball sits 1 unit in front of the eye.
    let seen = image(&scene(""));
    let clipped = image(&scene("near_clip = 1.5"));
    let wall_only = image(&scene("near_clip = 1.5").replace("radius = 0.05", "radius = 0.0001"));
    let ball = (0..64 * 64).find(|&i| {
        let (x, y) = (i % 64, i / 64);
        (seen.get(x, y) - wall_only.get(x, y)).length() > 0.1
    });
    assert!(ball.is_some(), "the ball is visible without clipping");
    // Clipped, the camera sees the wall through it (the ball still casts a
    // faint shadow and reflects a little light: a tolerance, not equality).
    let worst = clipped
        .pixels
        .iter()
        .zip(&wall_only.pixels)
        .map(|(a, b)| (*a - *b).abs().max_element())
        .fold(0.0f32, f32::max);
    assert!(worst < 0.05, "largest difference {worst}");
}

#[test]
fn pixel_filter_keys_are_read_and_checked() {
    use caustic::film::filter::PixelFilter;
    let filter = |keys: &str| load(&scene(keys)).unwrap().scene.camera.filter;
    assert_eq!(filter(""), PixelFilter::Box { radius: 0.5 });
    assert_eq!(filter("filter = \"tent\""), PixelFilter::Tent { radius: 1.0 });
    assert_eq!(
        filter("filter = \"box\"\nfilter_radius = 1.5"),
        PixelFilter::Box { radius: 1.5 }
    );
    assert_eq!(filter("filter = \"gaussian\""), PixelFilter::gaussian(0.5));
    assert_eq!(filter("filter = \"gaussian\"\nfilter_stddev = 0.7").radius(), 2.8);
    let error = |keys: &str| load(&scene(keys)).unwrap_err().to_string();
    let e = error("filter = \"mitchell\"");
    assert!(
        e.contains("camera.toml:11:10") && e.contains("unknown `filter` `mitchell`"),
        "{e}"
    );
    let e = error("filter = \"gaussian\"\nfilter_radius = 2");
    assert!(
        e.contains("camera.toml:12:17") && e.contains("4 × `filter_stddev`"),
        "{e}"
    );
    assert!(error("filter_stddev = 0.5").contains("applies to `filter = \"gaussian\"` only"));
    assert!(error("filter = \"tent\"\nfilter_radius = 0").contains("`filter_radius` = 0 must be in (0, 64]"));
    assert!(error("filter = \"gaussian\"\nfilter_stddev = 100").contains("must be in (0, 16]"));
}

#[test]
fn wider_filters_blur_and_keep_the_mean() {
    let sharp = image(&scene(""));
    let mean = |f: &Film| f.pixels.iter().map(|c| c.x as f64).sum::<f64>() / f.pixels.len() as f64;
    let mut previous = sharpness(&sharp);
    // Each wider than the last: the checkerboard's edges soften.
    for keys in [
        "filter = \"tent\"",
        "filter = \"gaussian\"\nfilter_stddev = 0.8",
        "filter = \"box\"\nfilter_radius = 2.5",
    ] {
        let film = image(&scene(keys));
        let s = sharpness(&film);
        assert!(
            s < 0.95 * previous,
            "{keys}: sharpness {s}, the narrower filter's {previous}"
        );
        previous = s;
        // The board is 50 % bright squares far from the border: filtering
        // moves light between pixels without losing it.
        assert!((mean(&film) / mean(&sharp) - 1.0).abs() < 0.02, "{keys}");
    }
}

#[test]
fn a_filtered_render_is_the_same_on_any_thread_count() {
    let text = scene("filter = \"gaussian\"\nfilter_stddev = 0.8");
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| image(&text))
    };
    assert!(on(1).pixels == on(2).pixels, "1 and 2 threads differ");
}

#[test]
fn orthographic_keys_are_read_and_checked() {
    let ortho = |keys: &str| scene(&format!("projection = \"orthographic\"\n{keys}")).replace("vfov = 30\n", "");
    let c = load(&ortho("half_width = 2\nhalf_height = 1.5")).unwrap().scene.camera;
    assert_eq!(
        c.projection,
        Projection::Orthographic {
            half_width: 2.0,
            half_height: 1.5
        }
    );
    // 64 × 64: the larger of the two extents wins.
    assert_eq!(c.half_extents(1.0), (2.0, 2.0));
    let error = |keys: &str| load(&ortho(keys)).unwrap_err().to_string();
    let e = error("");
    assert!(e.contains("needs `half_width` or `half_height`"), "{e}");
    for bad in ["half_width = 0", "half_height = -1", "half_width = nan"] {
        let e = error(bad);
        assert!(
            e.contains("camera.toml:11:") && (e.contains("must be > 0") || e.contains("finite")),
            "{bad}: {e}"
        );
    }
    let e = error("half_width = 1\naperture_radius = 0.1");
    assert!(e.contains("no lens"), "{e}");
    let e = load(&scene("projection = \"orthographic\"\nhalf_width = 1"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("`vfov` is a perspective camera's"), "{e}");
    let e = load(&scene("half_width = 1")).unwrap_err().to_string();
    assert!(e.contains("`half_width` is an orthographic camera's"), "{e}");
    let e = load(&scene("projection = \"fisheye\"")).unwrap_err().to_string();
    assert!(e.contains("unknown `projection` `fisheye`"), "{e}");
}

#[test]
fn an_orthographic_view_does_not_depend_on_the_distance() {
    // The 4 × 4 wall fills a view of half height 2 from any distance: the
    // images from 5 and 4.5 units away agree (the ball, at z = 4, is in
    // front of both).
    let at = |z: f32| {
        image(
            &scene("projection = \"orthographic\"\nhalf_height = 2")
                .replace("vfov = 30\n", "")
                .replace("position = [0.0, 0.0, 5.0]", &format!("position = [0.0, 0.0, {z}]")),
        )
    };
    let (a, b) = (at(5.0), at(4.5));
    let diff = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(p, q)| (*p - *q).abs().max_element())
        .fold(0.0, f32::max);
    assert!(diff < 1e-3, "{diff}");
    assert!(sharpness(&a) > 0.1, "{}", sharpness(&a));
    // The wall spans the view exactly: the border columns see the
    // checkerboard (half 0.9, half 0.05), not the white environment;
    // wider, they see the environment.
    let column = |f: &Film, x: u32| (0..64).map(|y| f.get(x, y).x).sum::<f32>() / 64.0;
    assert!(
        column(&a, 0) < 0.6 && column(&a, 63) < 0.6,
        "{} {}",
        column(&a, 0),
        column(&a, 63)
    );
    let wider = image(&scene("projection = \"orthographic\"\nhalf_height = 2.5").replace("vfov = 30\n", ""));
    assert!(column(&wider, 0) > 0.99 && column(&wider, 63) > 0.99);
}
