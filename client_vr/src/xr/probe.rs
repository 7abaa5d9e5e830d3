//! Is there an OpenXR runtime to play in? Asked once at start-up, before any window opens.
//!
//! Three answers: no loader library (nothing OpenXR installed), a loader but no runtime (Debian's
//! `libopenxr-loader1` alone answers `XR_ERROR_RUNTIME_UNAVAILABLE`), or a runtime — and then whether it
//! has a headset. Only the last with a headset starts XR; the others start the desktop mode, and
//! [`XrProbe::line`] is the one log line that says which and why.

use std::path::{Path, PathBuf};

/// The environment variable that names the loader library to use instead of the system's
/// (`libopenxr_loader.so` on the library path).
pub const LOADER_ENV: &str = "PHANTOM_OPENXR_LOADER";

/// What the probe found.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum XrProbe {
    /// A runtime with a head-mounted display: play in VR.
    Ready {
        /// The runtime's name and version.
        runtime: String,
    },
    /// A runtime, but it reports no headset.
    NoHeadset {
        /// The runtime's name and version.
        runtime: String,
        /// What it said.
        reason: String,
    },
    /// The loader library is present but no runtime is installed or active.
    NoRuntime {
        /// What the loader said.
        reason: String,
    },
    /// No OpenXR loader library could be opened.
    NoLoader {
        /// The library asked for and why it failed.
        reason: String,
    },
}

impl XrProbe {
    /// Whether XR mode can start.
    pub fn ready(&self) -> bool {
        matches!(self, XrProbe::Ready { .. })
    }

    /// The one log line about the choice.
    pub fn line(&self) -> String {
        match self {
            XrProbe::Ready { runtime } => format!("XR mode: OpenXR runtime {runtime} with a headset"),
            XrProbe::NoHeadset { runtime, reason } => {
                format!("desktop mode: OpenXR runtime {runtime} found but no headset ({reason})")
            }
            XrProbe::NoRuntime { reason } => {
                format!("desktop mode: OpenXR loader found but no OpenXR runtime is installed or active ({reason})")
            }
            XrProbe::NoLoader { reason } => format!("desktop mode: no OpenXR loader installed ({reason})"),
        }
    }
}

/// Probes with the loader named by [`LOADER_ENV`], or the system's.
pub fn probe_from_env() -> XrProbe {
    probe(std::env::var_os(LOADER_ENV).map(PathBuf::from).as_deref())
}

/// Probes with `loader` (a library path), or the system's loader when `None`.
pub fn probe(loader: Option<&Path>) -> XrProbe {
    // SAFETY: the library is the OpenXR loader (the system's, or the one the user named for this
    // purpose); loading it runs its initialisers, as any OpenXR application does.
    let entry = match loader {
        Some(path) => unsafe { openxr::Entry::load_from(path) }.map_err(|e| format!("{}: {e}", path.display())),
        None => unsafe { openxr::Entry::load() }.map_err(|e| format!("libopenxr_loader.so: {e}")),
    };
    let entry = match entry {
        Ok(entry) => entry,
        Err(reason) => return XrProbe::NoLoader { reason },
    };
    let app = openxr::ApplicationInfo {
        application_name: "Phantom Heist",
        application_version: 1,
        engine_name: "Bevy",
        engine_version: 19,
        api_version: openxr::Version::new(1, 0, 0),
    };
    let instance = match entry.create_instance(&app, &openxr::ExtensionSet::default(), &[]) {
        Ok(i) => i,
        Err(e) => return XrProbe::NoRuntime { reason: format!("{e:?}: {e}") },
    };
    let runtime = match instance.properties() {
        Ok(p) => format!("{} {}", p.runtime_name, p.runtime_version),
        Err(e) => format!("(unnamed: {e})"),
    };
    match instance.system(openxr::FormFactor::HEAD_MOUNTED_DISPLAY) {
        Ok(_) => XrProbe::Ready { runtime },
        Err(e) => XrProbe::NoHeadset { runtime, reason: format!("{e:?}: {e}") },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn with_no_loader_the_client_falls_back_to_the_desktop_and_says_why() {
        let p = probe(Some(Path::new("/nonexistent/libopenxr_loader.so.1")));
        assert!(matches!(p, XrProbe::NoLoader { .. }), "{p:?}");
        assert!(!p.ready());
        let line = p.line();
        assert!(line.starts_with("desktop mode: no OpenXR loader installed"), "{line}");
        assert!(line.contains("/nonexistent/libopenxr_loader.so.1"), "{line}");
    }

    #[test]
    fn lines_name_the_mode_and_the_reason() {
        let p = XrProbe::NoRuntime { reason: "XR_ERROR_RUNTIME_UNAVAILABLE".into() };
        assert!(p.line().contains("no OpenXR runtime") && p.line().contains("XR_ERROR_RUNTIME_UNAVAILABLE"));
        assert!(XrProbe::Ready { runtime: "Monado 25.0.0".into() }.line().starts_with("XR mode"));
        assert!(
            XrProbe::NoHeadset { runtime: "SteamVR".into(), reason: "x".into() }.line().starts_with("desktop mode")
        );
    }
}
