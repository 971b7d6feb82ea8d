//! State across animation frames (docs/DESIGN.md "Animation"): what a method says it
//! keeps from one animation frame to the next and what invalidates it (`AcrossFrames`, a
//! constant of every `RenderMethod`), and what the driver hands a render about its frame
//! (`AnimationFrame`: the frame's number and the previous frame's scene with what changed).
//!
//! Each animation frame is a render of its own (src/sequence.rs): the driver starts a new
//! accumulation every frame, so nothing but what a method keeps itself crosses frames. Every
//! built-in method but restir renders each frame from scratch (`AcrossFrames::NOTHING`, the
//! baseline every reuse is judged against); restir keeps its final reservoirs. A method that keeps tables, VPLs or reservoirs
//! declares them with the changes that invalidate them and keeps them in its kernels' object
//! (one per `Renderers`, which a sequence keeps for all its frames; behind a `RefCell`), with
//! the frame number they were made for. It reuses a piece only where `AnimationFrame::keeps`
//! says so: the previous frame was rendered just before by the same `Renderers` and nothing
//! that invalidates the piece changed. Where `previous` is None (a still, a sequence's first
//! frame, a frame after frames kept from disk) it drops what it holds. Only the previous
//! frame's CPU scene is handed on; its GPU scene (map texels, light table) and G-buffer are
//! gone by then, so a method that needs them (restir's temporal reuse across animation
//! frames) keeps its own copy.

use std::fmt;

use crate::scene::Scene;

/// A part of a frame's scene that an animation changes (docs/DESIGN.md "Animation": geometry
/// and materials other than emission stand still).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Change {
    /// Position, look-at or field of view.
    Camera,
    /// An analytic light's position, direction or intensity.
    Lights,
    /// An emissive material's radiance scale (area lights switching on and off).
    Emission,
    /// The environment map (a sequence's map or its rotation).
    Environment,
    /// A luminaire's placement or its atlas.
    Luminaires,
}

impl Change {
    pub const ALL: [Change; 5] = [
        Change::Camera,
        Change::Lights,
        Change::Emission,
        Change::Environment,
        Change::Luminaires,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Change::Camera => "camera",
            Change::Lights => "lights",
            Change::Emission => "emission",
            Change::Environment => "environment",
            Change::Luminaires => "luminaires",
        }
    }

    fn bit(self) -> u8 {
        1 << self as u8
    }
}

/// A set of changes.
#[derive(Clone, Copy, Default, PartialEq, Eq)]
pub struct Changes(u8);

impl Changes {
    pub const NONE: Changes = Changes(0);

    /// What differs between two frames' scenes (stills, as `Scene::at_frame` builds them).
    pub fn between(previous: &Scene, this: &Scene) -> Changes {
        let mut changes = Changes::NONE;
        let emission = |s: &Scene| s.materials.iter().map(|m| m.ke).collect::<Vec<_>>();
        let differs = [
            (Change::Camera, previous.camera != this.camera),
            (Change::Lights, previous.lights != this.lights),
            (Change::Emission, emission(previous) != emission(this)),
            (
                Change::Environment,
                previous.environment != this.environment,
            ),
            (Change::Luminaires, previous.luminaires != this.luminaires),
        ];
        for (change, differs) in differs {
            if differs {
                changes.0 |= change.bit();
            }
        }
        changes
    }

    pub fn with(self, change: Change) -> Changes {
        Changes(self.0 | change.bit())
    }

    pub fn contains(self, change: Change) -> bool {
        self.0 & change.bit() != 0
    }

    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// Whether any of `changes` is in the set.
    pub fn any_of(self, changes: &[Change]) -> bool {
        changes.iter().any(|&c| self.contains(c))
    }

    pub fn iter(self) -> impl Iterator<Item = Change> {
        Change::ALL.into_iter().filter(move |&c| self.contains(c))
    }
}

impl fmt::Debug for Changes {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_set()
            .entries(self.iter().map(Change::name))
            .finish()
    }
}

/// One piece of state a method carries from an animation frame to the next.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Carried {
    /// What it is, in a few words ("the VPLs", "each pixel's reservoir").
    pub state: &'static str,
    /// The changes after which it is dropped or re-evaluated.
    pub invalidated_by: &'static [Change],
}

/// What a method keeps from one animation frame to the next.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AcrossFrames {
    pub carries: &'static [Carried],
}

impl AcrossFrames {
    /// Each frame rendered from scratch.
    pub const NOTHING: AcrossFrames = AcrossFrames { carries: &[] };

    pub fn carries_nothing(&self) -> bool {
        self.carries.is_empty()
    }

    /// One line for `irad methods` and records.
    pub fn describe(&self) -> String {
        if self.carries.is_empty() {
            return "nothing: each animation frame is rendered from scratch".into();
        }
        let parts: Vec<String> = self
            .carries
            .iter()
            .map(|c| {
                let by: Vec<&str> = c.invalidated_by.iter().map(|x| x.name()).collect();
                match by.is_empty() {
                    true => format!("{} (kept through every change)", c.state),
                    false => format!("{} (invalidated by a change of {})", c.state, by.join(", ")),
                }
            })
            .collect();
        parts.join("; ")
    }
}

/// The previous animation frame of a render, as the driver hands it to the method.
#[derive(Clone, Copy)]
pub struct PreviousFrame<'a> {
    pub frame: u32,
    /// Its scene: camera, lights, emission, map and luminaires as that frame showed them.
    pub scene: &'a Scene,
    /// What differs from it in this frame's scene.
    pub changed: Changes,
}

/// Which animation frame a render shows.
#[derive(Clone, Copy)]
pub struct AnimationFrame<'a> {
    /// The frame's number (0 for a still).
    pub frame: u32,
    /// The frame rendered just before this one with the same `Renderers`, when it is this
    /// frame's predecessor in the animation and the method carries state across frames
    /// (`AcrossFrames`): None for a still render, for the first frame a sequence renders (a
    /// resumed sequence's too: no state is stored on disk), and for a method that keeps
    /// nothing.
    pub previous: Option<PreviousFrame<'a>>,
}

impl AnimationFrame<'_> {
    /// A still render (or one frame rendered alone).
    pub const STILL: AnimationFrame<'static> = AnimationFrame {
        frame: 0,
        previous: None,
    };

    /// Frame `frame` rendered alone.
    pub fn alone(frame: u32) -> AnimationFrame<'static> {
        AnimationFrame {
            frame,
            previous: None,
        }
    }

    /// Whether `carried`, as made for the previous frame, may be reused in this one: there
    /// is a previous frame and none of the changes that invalidate it happened.
    pub fn keeps(&self, carried: &Carried) -> bool {
        self.previous
            .is_some_and(|p| !p.changed.any_of(carried.invalidated_by))
    }
}
