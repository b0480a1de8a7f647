//! What an image shows (`--view`), by name on the command line, in the app's settings and in
//! the test hook, and by code in `ShadeParams.view` for shade.wgsl and its CPU port.

/// What the image shows (`--view`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum View {
    #[default]
    Shaded,
    Normals,
    Depth,
    HeatmapCells,
    HeatmapTests,
}

impl View {
    pub const ALL: [View; 5] = [View::Shaded, View::Normals, View::Depth, View::HeatmapCells, View::HeatmapTests];

    pub fn name(self) -> &'static str {
        match self {
            View::Shaded => "shaded",
            View::Normals => "normals",
            View::Depth => "depth",
            View::HeatmapCells => "heatmap-cells",
            View::HeatmapTests => "heatmap-tests",
        }
    }

    /// The code `ShadeParams.view` carries to shade.wgsl.
    pub fn code(self) -> u32 {
        self as u32
    }

    /// The view a [`View::code`] stands for.
    pub fn from_code(code: u32) -> Option<View> {
        View::ALL.into_iter().find(|v| v.code() == code)
    }

    /// A false-colour view of a per-ray count (the heatmap scale applies).
    pub fn is_heatmap(self) -> bool {
        matches!(self, View::HeatmapCells | View::HeatmapTests)
    }
}

impl std::str::FromStr for View {
    type Err = String;
    fn from_str(s: &str) -> Result<View, String> {
        View::ALL.into_iter().find(|v| v.name() == s).ok_or_else(|| {
            format!("unknown view \"{s}\": expected shaded, normals, depth, heatmap-cells or heatmap-tests")
        })
    }
}
