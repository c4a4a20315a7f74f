//! Hot loops of expressive-mocap. Pure kernels on slices; `py` (feature "python") adapts
//! them to NumPy. Every kernel has a NumPy twin in `expressive_mocap.reference`.

pub mod arms;
pub mod clip;
pub mod decode;
pub mod decouple;
pub mod error;
pub mod features;
pub mod fk;
pub mod footsteps;
pub mod format;
pub mod forms;
pub mod gait;
pub mod heads;
pub mod ik;
pub mod mlp;
pub mod parse;
pub mod planting;
pub mod retarget;
pub mod rotations;
pub mod smooth;
pub mod trig;
pub mod zeroable;

#[cfg(feature = "python")]
mod py;
