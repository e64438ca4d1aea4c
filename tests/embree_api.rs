//! The public Embree API end to end on a small scene: selection through
//! `accel::build`, version and origin, errors as values. Small on purpose:
//! this is the test to run under valgrind (the command is in
//! docs/commands.md, "Checking the Embree binding under valgrind").

mod common;

use caustic::accel::{build, AccelError, AccelKind, AccelOptions};

#[cfg(not(feature = "embree"))]
#[test]
fn embree_is_unavailable_without_the_feature() {
    assert_eq!(AccelKind::default_kind(), AccelKind::KdTree);
    let scene = common::scenes::test_scene();
    let err = build(&scene, AccelKind::Embree, &AccelOptions::default())
        .err()
        .expect("no Embree");
    assert!(matches!(err, AccelError::Unavailable("embree")), "{err}");
}

#[cfg(feature = "embree")]
mod with_embree {
    use super::*;
    use caustic::accel::embree::{self, Device};
    use caustic::accel::Accel;
    use caustic::math::{Ray, Vec3A};

    #[test]
    fn embree_is_the_default_and_reports_where_it_came_from() {
        assert_eq!(AccelKind::default_kind(), AccelKind::Embree);
        let version = embree::version();
        assert!(version.starts_with("4."), "{version}");
        let source = embree::source();
        assert!(
            source.starts_with("pkg-config") || source.starts_with("EMBREE_DIR") || source.starts_with("wheel"),
            "{source}"
        );
        eprintln!("Embree {version} from {source}");
    }

    #[test]
    fn small_scene_through_accel_build() {
        let scene = common::scenes::test_scene();
        let accel = build(&scene, AccelKind::Embree, &AccelOptions::default()).unwrap();
        let stats = accel.stats();
        assert_eq!(stats.name, "embree");
        assert!(stats.details.iter().any(|(k, v)| k == "version" && v.starts_with("4.")));
        // Down onto the floor quad (object 0), then a shadow query below it.
        let r = Ray::new(Vec3A::new(5.5, 10.0, 5.5), -Vec3A::Y);
        let hit = accel.intersect(&r, f32::INFINITY).unwrap();
        assert_eq!((hit.instance, hit.prim), (0, 0));
        assert!(accel.occluded(&r, 20.0));
        assert!(!accel.occluded(&r, 5.0));
        // A few hundred seeded rays over spheres, quads and instances (so a
        // valgrind run exercises every callback): same closest object as the oracle.
        let brute = caustic::accel::brute::BruteForce::new(&scene, caustic::accel::TriangleTest::Watertight);
        let mut hits = 0;
        for i in 0..400 {
            let r = common::scenes::ray(&scene, 99, i);
            let (e, b) = (accel.intersect(&r, f32::INFINITY), brute.intersect(&r, f32::INFINITY));
            assert_eq!(e.map(|h| h.instance), b.map(|h| h.instance), "ray {i}: {r:?}");
            assert_eq!(accel.occluded(&r, f32::INFINITY), b.is_some(), "ray {i}: {r:?}");
            hits += e.is_some() as usize;
        }
        assert!(hits > 100, "{hits}");
        // Several accelerators alive at once, dropped in any order.
        let second = build(&scene, AccelKind::Embree, &AccelOptions::default()).unwrap();
        drop(accel);
        assert_eq!(second.intersect(&r, f32::INFINITY).unwrap().instance, 0);
    }

    #[test]
    fn errors_are_values_not_panics() {
        match Device::new(Some("verbose=abc")) {
            Err(AccelError::Embree(m)) => assert!(m.contains("rtcNewDevice"), "{m}"),
            Err(other) => panic!("wrong error kind: {other}"),
            Ok(_) => panic!("Embree accepted an invalid config"),
        }
        let scene = common::scenes::test_scene();
        let options = AccelOptions {
            embree_quality: "ultra".into(),
            ..Default::default()
        };
        let err = build(&scene, AccelKind::Embree, &options)
            .err()
            .expect("bad quality rejected");
        assert!(err.to_string().contains("ultra"), "{err}");
    }
}
