//! Hybrid packets: 8 rays down the binary tree together while they stay together, then each
//! remaining ray alone down the 8-wide tree (Embree's hybrid intersector switches the same
//! way, by the number of rays still active at a node).
//!
//! The packet part is `traverse8` (shared with the packet engine, which never switches): each
//! visited node carries the mask of the lanes whose ray meets its box. When it has at most
//! [`SWITCH`] lanes and the node has a twin in the wide tree (`Bvh8::entry`), every such lane
//! walks that wide subtree single-ray from its current closest hit. Results are bit for bit
//! `intersect1`'s: each lane's answer is the smallest `(t, triangle)` among the triangles its
//! ray meets in the subtrees it visits, however they are split between the two walks.

use super::Accel;
use super::packet::traverse8;
use crate::packet::{HitPacket8, RayPacket8};
use crate::simd::M32x8;

pub use super::hand_off::SWITCH;

/// Closest hits of the `active` lanes, hybrid (equals `intersect8` and `intersect1` bit for bit).
pub fn intersect_hybrid8(
    accel: &Accel,
    rays: &RayPacket8,
    active: M32x8,
    cull: bool,
) -> HitPacket8 {
    traverse8::<false, SWITCH>(accel, rays, active, cull).0
}

/// Lanes of `active` whose ray hits anything with `tnear < t < tfar`, hybrid.
pub fn occluded_hybrid8(accel: &Accel, rays: &RayPacket8, active: M32x8, cull: bool) -> M32x8 {
    traverse8::<true, SWITCH>(accel, rays, active, cull).1
}
