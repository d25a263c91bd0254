//! glTF accessors read safely: an accessor's type, component type, stride and count are
//! checked against its buffer view and buffer before any element is read.

use super::{Accessor, Document, at};
use crate::error::Result;
use std::borrow::Cow;
use std::path::Path;

/// An accessor's elements, bounds checked: where they are and how to read them.
pub(super) struct View<'a> {
    /// The buffer view's bytes.
    bytes: &'a [u8],
    /// Offset of element 0 in `bytes`.
    start: usize,
    /// Bytes from one element to the next.
    stride: usize,
    /// `componentType`.
    component: u32,
    /// Number of elements.
    pub(super) count: usize,
    /// Normalised integers (read into 0..=1).
    normalized: bool,
}

/// Bytes of one component of `componentType`, if glTF defines it.
fn component_size(t: u32) -> Option<usize> {
    match t {
        5120 | 5121 => Some(1),
        5122 | 5123 => Some(2),
        5125 | 5126 => Some(4),
        _ => None,
    }
}

impl View<'_> {
    /// Component `c` of element `k` as a float (normalised integers into 0..=1; signed
    /// normalised into -1..=1).
    pub(super) fn float(&self, k: usize, c: usize) -> f32 {
        let size = component_size(self.component).expect("checked");
        let at = self.start + k * self.stride + c * size;
        let b = &self.bytes[at..at + size];
        let raw = match self.component {
            5126 => return f32::from_le_bytes(b.try_into().expect("4 bytes")),
            5120 => b[0] as i8 as f32,
            5121 => b[0] as f32,
            5122 => i16::from_le_bytes(b.try_into().expect("2 bytes")) as f32,
            5123 => u16::from_le_bytes(b.try_into().expect("2 bytes")) as f32,
            _ => u32::from_le_bytes(b.try_into().expect("4 bytes")) as f32,
        };
        if !self.normalized {
            return raw;
        }
        match self.component {
            5120 => (raw / 127.0).max(-1.0),
            5121 => raw / 255.0,
            5122 => (raw / 32767.0).max(-1.0),
            5123 => raw / 65535.0,
            _ => raw,
        }
    }

    /// Element `k` of an unsigned integer scalar accessor.
    pub(super) fn index(&self, k: usize) -> u32 {
        let at = self.start + k * self.stride;
        let b = &self.bytes[at..];
        match self.component {
            5121 => b[0] as u32,
            5123 => u16::from_le_bytes([b[0], b[1]]) as u32,
            _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        }
    }
}

/// Accessor `i`, checked: its type is one of `kinds` and its component type one of
/// `components`, and every element lies inside its buffer view, inside its buffer.
pub(super) fn view<'a>(
    doc: &Document,
    buffers: &'a [Cow<'a, [u8]>],
    i: usize,
    kinds: &[&str],
    components: &[u32],
    used_as: &str,
    path: &Path,
) -> Result<View<'a>> {
    let key = format!("accessors[{i}]");
    let a: &Accessor = doc.accessors.get(i).ok_or_else(|| {
        at(
            path,
            used_as,
            format!("no accessor {i} (the file has {})", doc.accessors.len()),
        )
    })?;
    if a.sparse.is_some() {
        return Err(at(
            path,
            &format!("{key}.sparse"),
            "sparse accessors are not read",
        ));
    }
    let width = match a.kind.as_str() {
        "SCALAR" => 1,
        "VEC2" => 2,
        "VEC3" => 3,
        "VEC4" => 4,
        _ => 0,
    };
    if width == 0 || !kinds.contains(&a.kind.as_str()) {
        return Err(at(
            path,
            &format!("{key}.type"),
            format!(
                "'{}' as {used_as}, which takes {}",
                a.kind,
                kinds.join(" or ")
            ),
        ));
    }
    let size = component_size(a.component_type)
        .filter(|_| components.contains(&a.component_type))
        .ok_or_else(|| {
            at(
                path,
                &format!("{key}.componentType"),
                format!("{} is not read as {used_as}", a.component_type),
            )
        })?;
    let bv_index = a.buffer_view.ok_or_else(|| {
        at(
            path,
            &format!("{key}.bufferView"),
            "missing (accessors without data are not read)",
        )
    })?;
    let bv_key = format!("bufferViews[{bv_index}]");
    let bv = doc.buffer_views.get(bv_index).ok_or_else(|| {
        at(
            path,
            &format!("{key}.bufferView"),
            format!("no buffer view {bv_index}"),
        )
    })?;
    let buffer = buffers.get(bv.buffer).ok_or_else(|| {
        at(
            path,
            &format!("{bv_key}.buffer"),
            format!("no buffer {}", bv.buffer),
        )
    })?;
    let end = bv.byte_offset.checked_add(bv.byte_length);
    if end.is_none_or(|e| e > buffer.len() as u64) {
        return Err(at(
            path,
            &format!("{bv_key}.byteLength"),
            format!(
                "bytes {}..{} are outside buffer {} ({} bytes)",
                bv.byte_offset,
                bv.byte_offset as u128 + bv.byte_length as u128,
                bv.buffer,
                buffer.len()
            ),
        ));
    }
    let bytes = &buffer[bv.byte_offset as usize..(bv.byte_offset + bv.byte_length) as usize];
    let element = (size * width) as u64;
    let stride = bv.byte_stride.unwrap_or(element);
    if stride < element || stride % size as u64 != 0 || stride > 252 {
        return Err(at(
            path,
            &format!("{bv_key}.byteStride"),
            format!(
                "{stride} for elements of {element} bytes (a multiple of {size}, at least {element}, at most 252)"
            ),
        ));
    }
    if a.count == 0 {
        return Err(at(path, &format!("{key}.count"), "0 elements"));
    }
    // The last element's end, in u128: a count of 10^18 cannot overflow the check.
    let last_end = a.byte_offset as u128 + (a.count as u128 - 1) * stride as u128 + element as u128;
    if last_end > bytes.len() as u128 {
        return Err(at(
            path,
            &format!("{key}.count"),
            format!(
                "{} elements of {element} bytes every {stride} from byte {} need {last_end} bytes; buffer view {bv_index} has {}",
                a.count,
                a.byte_offset,
                bytes.len()
            ),
        ));
    }
    Ok(View {
        bytes,
        start: a.byte_offset as usize,
        stride: stride as usize,
        component: a.component_type,
        count: a.count as usize,
        normalized: a.normalized,
    })
}
