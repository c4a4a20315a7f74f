//! Per-frame dynamic features of a motion (METHODS.md part 2): hips velocity and its 1/3 s
//! mean in the heading frame, foot contacts, air time, relative hips height, thigh rotations.
