//! The one list of methods: a `Registry` holds each method's entry, the `RenderMethod`
//! implementation with its type erased, so that code which picks a method by name (the CLI,
//! suite files, records) reaches its settings table, its constants and its render.
//! `Registry::builtin()` lists irad's own; `Registry::with` adds a method defined anywhere,
//! in this crate or outside it (examples/custom_method.rs).

use std::any::{Any, TypeId};
use std::collections::BTreeMap;
use std::fmt;
use std::marker::PhantomData;
use std::sync::{Arc, OnceLock};

use crate::gpu::Context;
use crate::scene::gpu::GpuScene;
use crate::scene::Scene;

use super::across_frames::{AcrossFrames, AnimationFrame};
use super::interface::{self, RenderMethod};
use super::lights::Lights;
use super::settings::{self, ParamError, SettingDoc, Value};
use super::{bir, bundles, envmap, ir, lightfield, reference, restir};
use super::{Method, RenderOutput, Renderers, RunError};

/// irad's methods, in the order `irad methods` lists them. A new method of irad's is one
/// line here.
fn builtin_registry() -> Registry {
    Registry::empty()
        .with::<reference::Reference>()
        .with::<ir::InstantRadiosity>()
        .with::<bir::Bir>()
        .with::<bundles::Bundles>()
        .with::<envmap::Env>()
        .with::<lightfield::Lightfield>()
        .with::<restir::Restir>()
}

/// Methods by name.
#[derive(Clone)]
pub struct Registry {
    entries: Vec<&'static dyn MethodEntry>,
}

impl Registry {
    /// No methods.
    pub fn empty() -> Registry {
        Registry {
            entries: Vec::new(),
        }
    }

    /// irad's own methods.
    pub fn builtin() -> &'static Registry {
        static BUILTIN: OnceLock<Registry> = OnceLock::new();
        BUILTIN.get_or_init(builtin_registry)
    }

    /// These methods and `M`.
    ///
    /// Panics where `M`'s name is taken or its table lacks the Count rows `seed` and
    /// `M::COUNT` (a method's code is wrong, whatever the input).
    pub fn with<M: RenderMethod>(mut self) -> Registry {
        interface::assert_table::<M>();
        assert!(
            self.get(M::NAME).is_err(),
            "cannot register method {}: the name is taken",
            M::NAME
        );
        self.entries.push(entry::<M>());
        self
    }

    /// Every method's entry, in order.
    pub fn entries(&self) -> &[&'static dyn MethodEntry] {
        &self.entries
    }

    /// Every method's name, in order.
    pub fn names(&self) -> Vec<&'static str> {
        self.entries.iter().map(|e| e.name()).collect()
    }

    /// The method named `name`.
    pub fn get(&self, name: &str) -> Result<&'static dyn MethodEntry, ParamError> {
        self.entries
            .iter()
            .find(|e| e.name() == name)
            .copied()
            .ok_or_else(|| ParamError::UnknownMethod {
                name: name.to_string(),
                known: self.names().join(", "),
            })
    }

    /// `name` with `params` (a suite file's table: keys and values as `irad methods` lists
    /// them) over its settings' defaults. Unknown keys, values out of range and settings
    /// that do not apply are errors naming the method, key and value.
    pub fn from_params(&self, name: &str, params: &toml::Table) -> Result<Method, ParamError> {
        self.get(name)?.method_from_toml(params)
    }

    /// `name` with `given` (key, value as written, value checked against the key's kind in
    /// `settings(name)`; the CLI's flags) over its defaults.
    pub fn from_values(
        &self,
        name: &str,
        given: &[(&str, String, Value)],
    ) -> Result<Method, ParamError> {
        self.get(name)?.method_from_values(given)
    }

    /// The settings `name` takes, with their defaults, in table order.
    pub fn settings(&self, name: &str) -> Result<Vec<SettingDoc>, ParamError> {
        Ok(self.get(name)?.docs())
    }
}

/// A method with its type erased: what the registry and `Method` reach. Implemented for every
/// `RenderMethod` and sealed (settings pass as `&dyn Any` holding the method's `Settings`,
/// which only the generic implementation can promise).
pub trait MethodEntry: sealed::Sealed + Sync {
    fn name(&self) -> &'static str;
    fn summary(&self) -> &'static str;
    fn lights(&self) -> Lights;
    /// `RenderMethod::ACROSS_FRAMES`.
    fn across_frames(&self) -> AcrossFrames;
    /// `RenderMethod::across_frames` of these settings.
    fn across_frames_with(&self, s: &dyn Any) -> AcrossFrames;
    /// `RenderMethod::COUNT`.
    fn count_key(&self) -> &'static str;
    fn docs(&self) -> Vec<SettingDoc>;
    fn method_from_toml(&self, params: &toml::Table) -> Result<Method, ParamError>;
    fn method_from_values(&self, given: &[(&str, String, Value)]) -> Result<Method, ParamError>;
    /// The `TypeId` of the method type (for `Method::settings_of`).
    fn method_type(&self) -> TypeId;

    fn seed(&self, s: &dyn Any) -> u32;
    fn count(&self, s: &dyn Any) -> u32;
    fn with_seed(&self, s: &dyn Any, seed: u32) -> Arc<dyn Any + Send + Sync>;
    fn with_count(&self, s: &dyn Any, count: u32) -> Arc<dyn Any + Send + Sync>;
    fn work(&self, s: &dyn Any) -> f64;
    /// The table's values (unset ones and those that do not apply left out) and the
    /// record's notes, seed included.
    fn parameters(&self, s: &dyn Any) -> BTreeMap<String, serde_json::Value>;
    fn fits(&self, s: &dyn Any, scene: &Scene, limit: u64) -> Result<(), String>;
    fn equal(&self, a: &dyn Any, b: &dyn Any) -> bool;
    fn debug(&self, s: &dyn Any, f: &mut fmt::Formatter<'_>) -> fmt::Result;
    #[allow(clippy::too_many_arguments)]
    fn run(
        &self,
        renderers: &Renderers,
        ctx: &Context,
        s: &dyn Any,
        scene: &Scene,
        gpu_scene: &GpuScene,
        animation: &AnimationFrame<'_>,
        progress: &mut dyn FnMut(u32, u32),
    ) -> Result<RenderOutput, RunError>;
}

/// `M`'s entry.
pub(crate) fn entry<M: RenderMethod>() -> &'static dyn MethodEntry {
    <M as EntryOf>::ENTRY
}

trait EntryOf {
    const ENTRY: &'static dyn MethodEntry;
}

impl<M: RenderMethod> EntryOf for M {
    const ENTRY: &'static dyn MethodEntry = &Entry::<M>(PhantomData);
}

struct Entry<M>(PhantomData<fn() -> M>);

mod sealed {
    pub trait Sealed {}
    impl<M: super::RenderMethod> Sealed for super::Entry<M> {}
}

/// `s` as `M`'s settings: a `Method` pairs an entry with its own method's settings only.
fn settings_of<M: RenderMethod>(s: &dyn Any) -> &M::Settings {
    s.downcast_ref()
        .expect("a Method holds its own method's settings")
}

impl<M: RenderMethod> MethodEntry for Entry<M> {
    fn name(&self) -> &'static str {
        M::NAME
    }

    fn summary(&self) -> &'static str {
        M::SUMMARY
    }

    fn lights(&self) -> Lights {
        M::LIGHTS
    }

    fn across_frames(&self) -> AcrossFrames {
        M::ACROSS_FRAMES
    }

    fn across_frames_with(&self, s: &dyn Any) -> AcrossFrames {
        M::across_frames(settings_of::<M>(s))
    }

    fn count_key(&self) -> &'static str {
        M::COUNT
    }

    fn docs(&self) -> Vec<SettingDoc> {
        settings::docs(M::SETTINGS)
    }

    fn method_from_toml(&self, params: &toml::Table) -> Result<Method, ParamError> {
        Ok(Method::new::<M>(settings::from_toml(
            M::NAME,
            M::SETTINGS,
            params,
        )?))
    }

    fn method_from_values(&self, given: &[(&str, String, Value)]) -> Result<Method, ParamError> {
        Ok(Method::new::<M>(settings::build(
            M::NAME,
            M::SETTINGS,
            given,
        )?))
    }

    fn method_type(&self) -> TypeId {
        TypeId::of::<M>()
    }

    fn seed(&self, s: &dyn Any) -> u32 {
        interface::seed::<M>(settings_of::<M>(s))
    }

    fn count(&self, s: &dyn Any) -> u32 {
        interface::count::<M>(settings_of::<M>(s))
    }

    fn with_seed(&self, s: &dyn Any, seed: u32) -> Arc<dyn Any + Send + Sync> {
        let mut s = settings_of::<M>(s).clone();
        interface::set_seed::<M>(&mut s, seed);
        Arc::new(s)
    }

    fn with_count(&self, s: &dyn Any, count: u32) -> Arc<dyn Any + Send + Sync> {
        let mut s = settings_of::<M>(s).clone();
        interface::set_count::<M>(&mut s, count);
        Arc::new(s)
    }

    fn work(&self, s: &dyn Any) -> f64 {
        M::work(settings_of::<M>(s))
    }

    fn parameters(&self, s: &dyn Any) -> BTreeMap<String, serde_json::Value> {
        let s = settings_of::<M>(s);
        let mut p = settings::values(M::SETTINGS, s);
        for (key, value) in M::record_notes(s) {
            p.insert(key.to_string(), value);
        }
        p
    }

    fn fits(&self, s: &dyn Any, scene: &Scene, limit: u64) -> Result<(), String> {
        M::fits(settings_of::<M>(s), scene, limit)
    }

    fn equal(&self, a: &dyn Any, b: &dyn Any) -> bool {
        settings_of::<M>(a) == settings_of::<M>(b)
    }

    fn debug(&self, s: &dyn Any, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(settings_of::<M>(s), f)
    }

    fn run(
        &self,
        renderers: &Renderers,
        ctx: &Context,
        s: &dyn Any,
        scene: &Scene,
        gpu_scene: &GpuScene,
        animation: &AnimationFrame<'_>,
        progress: &mut dyn FnMut(u32, u32),
    ) -> Result<RenderOutput, RunError> {
        let (passes, method) = renderers.kernels::<M>(ctx)?;
        interface::render(
            passes,
            &*method,
            ctx,
            scene,
            gpu_scene,
            settings_of::<M>(s),
            animation,
            progress,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_method_serves_the_interface() {
        let names = Registry::builtin().names();
        assert_eq!(
            names,
            [
                "reference",
                "ir",
                "bir",
                "bundles",
                "env",
                "lightfield",
                "restir"
            ]
        );
        for e in Registry::builtin().entries() {
            let m = e.method_from_toml(&toml::Table::new()).unwrap();
            assert_eq!(m.with_seed(7).seed(), 7, "{}", e.name());
            assert_eq!(m.with_count(5).samples(), 5, "{}", e.name());
            assert_eq!(m.with_count(5).with_seed(3), m.with_seed(3).with_count(5));
        }
        let Err(e) = Registry::builtin().get("nothing") else {
            panic!("a method named nothing")
        };
        assert_eq!(
            e.to_string(),
            "unknown method `nothing` (methods: reference, ir, bir, bundles, env, lightfield, \
             restir)"
        );
    }

    #[test]
    #[should_panic(expected = "cannot register method ir: the name is taken")]
    fn a_name_is_registered_once() {
        let _ = Registry::builtin().clone().with::<ir::InstantRadiosity>();
    }
}
