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
//!
//! Any hit goes the other way: the 8 rays down the wide tree together from the root, each
//! alone once few remain (`wide8`, as `hybrid16`'s any hit with AVX-512). A shadow ray's walk
//! needs no order, so the packet loses nothing by taking a node's 8 children at once, and
//! it fetches the wide tree's nodes and blocks where the binary walk fetched twice as many
//! nodes and the triangle columns.

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

/// Lanes of `active` whose ray hits anything with `tnear < t < tfar`: the 8 rays down the
/// wide tree together, each alone once few remain (`wide8`; equals `occluded8` and
/// `occluded1`). At 1.3M triangles 1.2-1.3x as fast on the bench's shadow rays as down the
/// binary tree, the kitten level to 1.03x (docs/engines.md).
pub fn occluded_hybrid8(accel: &Accel, rays: &RayPacket8, active: M32x8, cull: bool) -> M32x8 {
    super::wide8::occluded_wide8(accel, rays, active, cull)
}
