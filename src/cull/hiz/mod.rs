//! Two-phase hierarchical-depth culling (issue 20), the technique Unreal,
//! Bevy and niagara ship: boxes are tested in a compute shader against a
//! pyramid of the depth drawn so far. Built a part at a time: so far the
//! depth pyramid ([`pyramid`]); the mode comes next.

pub mod pyramid;
