//! [`Resources`]: what the stages of one pipeline share while it is built.

/// Values the stages of one pipeline share while it is built, one per type (in the spirit of
/// Bevy's `Resource`): the first stage that needs one makes it, the next ones take it.
/// [`Pipeline::build`](super::Pipeline::build) makes a fresh set per pipeline, so nothing is shared between scenes.
#[derive(Default)]
pub struct Resources {
    map: std::collections::HashMap<std::any::TypeId, Box<dyn std::any::Any + Send + Sync>>,
}

impl Resources {
    /// The value of type `T`, if a stage put one in.
    pub fn get<T: std::any::Any + Send + Sync>(&self) -> Option<&T> {
        self.map
            .get(&std::any::TypeId::of::<T>())
            .and_then(|b| b.downcast_ref())
    }

    /// The value of type `T`: the one already there, else the one `make` returns (kept for
    /// the stages built after; an error is passed on and nothing kept).
    pub fn get_or_try_insert_with<T: std::any::Any + Send + Sync, E>(
        &mut self,
        make: impl FnOnce() -> Result<T, E>,
    ) -> Result<&T, E> {
        use std::collections::hash_map::Entry;
        let slot = match self.map.entry(std::any::TypeId::of::<T>()) {
            Entry::Occupied(o) => o.into_mut(),
            Entry::Vacant(v) => v.insert(Box::new(make()?)),
        };
        Ok(slot
            .downcast_ref()
            .expect("every value is keyed by its own type's id"))
    }
}
