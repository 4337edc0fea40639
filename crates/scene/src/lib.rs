//! The typed scene: camera, shapes and their BVH, emitters; and the loaders that build it
//! (Mitsuba 3 XML, PLY and OBJ meshes).

pub mod description;

pub use description::*;
