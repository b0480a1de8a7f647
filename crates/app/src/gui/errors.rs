//! The app's one list of errors, each tagged with where it came from, so the stats panel and
//! the test hook show the same thing and each kind is cleared by its own event: a GPU setup
//! failure stays, a build failure holds until the settings or the scene change (and stops the
//! same configuration from being retried), a render failure until the next finished frame, and
//! anything else until the user dismisses it.

use gridrt_grid::GridConfig;

/// Where an error came from. The build's whole configuration is kept (to compare with the next
/// one), so the enum is large; the app holds at most one error of each kind.
#[derive(Clone, Copy, Debug, PartialEq)]
#[allow(clippy::large_enum_variant)]
pub enum ErrorKind {
    /// The GPU could not be set up.
    Gpu,
    /// Building or uploading this configuration failed.
    Build(GridConfig),
    /// Rendering a frame failed.
    Render,
    /// Loading, saving, measuring or reading a frame back failed.
    Other,
}

#[derive(Debug, Default)]
pub struct Errors(Vec<(ErrorKind, String)>);

impl Errors {
    /// Reports `message`, replacing an earlier error of the same kind (any build error for a
    /// build error).
    pub fn report(&mut self, kind: ErrorKind, message: impl Into<String>) {
        self.0.retain(|(k, _)| std::mem::discriminant(k) != std::mem::discriminant(&kind));
        self.0.push((kind, message.into()));
    }

    /// Forgets the errors `drop` selects.
    pub fn clear(&mut self, drop: impl Fn(&ErrorKind) -> bool) {
        self.0.retain(|(k, _)| !drop(k));
    }

    /// Forgets the build error.
    pub fn clear_build(&mut self) {
        self.clear(|k| matches!(k, ErrorKind::Build(_)));
    }

    /// Whether building `config` failed (and so is not retried).
    pub fn build_failed(&self, config: &GridConfig) -> bool {
        self.0.iter().any(|(k, _)| *k == ErrorKind::Build(*config))
    }

    pub fn iter(&self) -> impl Iterator<Item = &(ErrorKind, String)> {
        self.0.iter()
    }

    /// Every message, joined by "; " (`None` without errors).
    pub fn joined(&self) -> Option<String> {
        (!self.0.is_empty()).then(|| self.0.iter().map(|(_, m)| m.as_str()).collect::<Vec<_>>().join("; "))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_kind_holds_one_error_and_clears_on_its_own_event() {
        let mut e = Errors::default();
        let cfg = GridConfig::default();
        e.report(ErrorKind::Build(cfg), "build a");
        e.report(ErrorKind::Other, "load");
        e.report(ErrorKind::Build(cfg), "build b");
        assert!(e.build_failed(&cfg));
        assert_eq!(e.joined().as_deref(), Some("load; build b"));
        e.clear(|k| *k == ErrorKind::Other);
        e.clear_build();
        assert!(!e.build_failed(&cfg) && e.joined().is_none());
    }
}
