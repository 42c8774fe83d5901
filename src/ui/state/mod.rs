//! The app's state: what the user loaded and decided ([`session`], [`setup`], saved and undoable),
//! what they are looking at ([`ViewState`], transient), and the [`command`]s that change either.
pub mod command;
pub mod session;
pub mod setup;
mod tab;
mod view_state;

pub use tab::Tab;
pub use view_state::{ViewState, ViewStates};
