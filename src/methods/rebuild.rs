//! When a method rebuilds the sampling tables it derives from a light's data (env's cube map,
//! CDFs, latitude-longitude table and pyramid; bundles' direction table; lightfield's luminaire
//! tables): once for a still map or atlas, every frame for a sequence or the procedural sky
//! (docs/DESIGN.md principle 9: build a table once unless its input changes). Lu 14 rebuilds every
//! frame (its maps are dynamic); `EveryFrame` keeps that for timing the dynamic case. The
//! kernels are deterministic, so a still input gives the same bits either way.

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TableRebuild {
    /// At frame 0, and every frame whose input differs from the last's.
    #[default]
    WhenChanged,
    /// Every frame (Lu 14's dynamic pipeline).
    EveryFrame,
}

crate::methods::settings::named_choices!(TableRebuild {
    WhenChanged => "when-changed",
    EveryFrame => "every-frame",
});

impl TableRebuild {
    /// Whether `frame` builds a table whose input changes from frame to frame when
    /// `sequence`.
    pub fn due(self, frame: u32, sequence: bool) -> bool {
        frame == 0 || sequence || self == TableRebuild::EveryFrame
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_still_input_builds_once_unless_every_frame_is_asked() {
        let when = TableRebuild::WhenChanged;
        assert!(when.due(0, false) && !when.due(1, false) && !when.due(7, false));
        assert!(when.due(1, true) && when.due(7, true));
        assert!(TableRebuild::EveryFrame.due(5, false));
    }
}
