//! The keywords of an Abaqus deck, one method of the parser each: what a keyword's options
//! and data lines add to the deck, and the errors that name the line.

mod analysis;
mod interaction;
mod lists;
mod loads;
mod mesh;
mod step;

pub(super) use lists::{ignored, not_modelled};
