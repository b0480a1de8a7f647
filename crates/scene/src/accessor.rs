//! Bounds-checked reads of glTF accessors: a buffer view's bytes, and an accessor's elements
//! as numbers (dense, all-zero without a buffer view, and with sparse substitution). The
//! `gltf` crate's readers panic or allocate on crafted input; these return an
//! [`AccessorFault`] that the caller turns into an error naming the accessor. Element counts
//! were checked against the load budget ([`crate::load_budget`]) before any of this runs.

use gltf::accessor::{Accessor, DataType};
use gltf::buffer::View;

/// Why an accessor cannot be read; the caller adds where it is.
#[derive(Debug)]
pub(crate) enum AccessorFault {
    /// Bytes the accessor needs lie outside its buffer view or buffer.
    OutOfBounds(String),
    /// The accessor's own description is inconsistent.
    Invalid(String),
}

/// `count` elements of `elem` bytes at `offset` in `view`: the bytes from the first element to
/// the end of the last, and the stride.
pub(crate) fn view_bytes<'a>(
    buffers: &[&'a [u8]],
    view: &View,
    offset: usize,
    count: usize,
    elem: usize,
) -> Result<(&'a [u8], usize), AccessorFault> {
    let stride = view.stride().unwrap_or(elem);
    if stride < elem {
        return Err(AccessorFault::Invalid(format!("byteStride {stride} is smaller than the element size {elem}")));
    }
    let buffer = view.buffer().index();
    let data =
        buffers.get(buffer).copied().ok_or_else(|| AccessorFault::OutOfBounds(format!("buffer {buffer} missing")))?;
    let view_end = view.offset().checked_add(view.length());
    if view_end.is_none_or(|e| e > data.len()) {
        return Err(AccessorFault::OutOfBounds(format!(
            "buffer view {} spans bytes {}..{} of a {}-byte buffer",
            view.index(),
            view.offset(),
            view.offset() as u128 + view.length() as u128,
            data.len()
        )));
    }
    let view_bytes = &data[view.offset()..view.offset() + view.length()];
    if count == 0 {
        return Ok((&[], stride));
    }
    // u128: a crafted count can overflow u64 arithmetic on 32-bit targets.
    let need = offset as u128 + stride as u128 * (count as u128 - 1) + elem as u128;
    if need > view_bytes.len() as u128 {
        return Err(AccessorFault::OutOfBounds(format!(
            "{count} elements of {elem} bytes (stride {stride}, offset {offset}) need {need} bytes, buffer view {} has {}",
            view.index(),
            view_bytes.len()
        )));
    }
    Ok((&view_bytes[offset..need as usize], stride))
}

/// Bytes of one component of `t`.
fn component_size(t: DataType) -> usize {
    match t {
        DataType::I8 | DataType::U8 => 1,
        DataType::I16 | DataType::U16 => 2,
        DataType::U32 | DataType::F32 => 4,
    }
}

/// Component `k` of the element at `b` as f64 (normalized integers mapped by the glTF rules).
fn component(b: &[u8], t: DataType, normalized: bool, k: usize) -> f64 {
    let s = component_size(t);
    let c = &b[k * s..k * s + s];
    let raw = match t {
        DataType::I8 => c[0] as i8 as f64,
        DataType::U8 => c[0] as f64,
        DataType::I16 => i16::from_le_bytes([c[0], c[1]]) as f64,
        DataType::U16 => u16::from_le_bytes([c[0], c[1]]) as f64,
        DataType::U32 => u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64,
        DataType::F32 => f32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64,
    };
    if !normalized {
        return raw;
    }
    match t {
        DataType::I8 => (raw / 127.0).max(-1.0),
        DataType::U8 => raw / 255.0,
        DataType::I16 => (raw / 32767.0).max(-1.0),
        DataType::U16 => raw / 65535.0,
        _ => raw,
    }
}

/// Every component of every element of `acc`, in order, as f64: the buffer view's data (or
/// zeros without one), then the sparse substitutions.
pub(crate) fn read_components(buffers: &[&[u8]], acc: &Accessor) -> Result<Vec<f64>, AccessorFault> {
    let count = acc.count();
    let n = acc.dimensions().multiplicity();
    let (t, normalized) = (acc.data_type(), acc.normalized());
    let elem = component_size(t) * n;
    let decode = |b: &[u8], out: &mut Vec<f64>| (0..n).for_each(|k| out.push(component(b, t, normalized, k)));
    let mut out = Vec::with_capacity(count * n);
    match acc.view() {
        Some(view) => {
            let (bytes, stride) = view_bytes(buffers, &view, acc.offset(), count, elem)?;
            for i in 0..count {
                decode(&bytes[i * stride..], &mut out);
            }
        }
        None => out.resize(count * n, 0.0),
    }
    if let Some(sparse) = acc.sparse() {
        let m = sparse.count();
        if m > count {
            return Err(AccessorFault::Invalid(format!("sparse count {m} exceeds the accessor count {count}")));
        }
        let idx = sparse.indices();
        let isize = match idx.index_type() {
            gltf::accessor::sparse::IndexType::U8 => 1,
            gltf::accessor::sparse::IndexType::U16 => 2,
            gltf::accessor::sparse::IndexType::U32 => 4,
        };
        let (ib, _) = view_bytes(buffers, &idx.view(), idx.offset(), m, isize)?;
        let vals = sparse.values();
        let (vb, _) = view_bytes(buffers, &vals.view(), vals.offset(), m, elem)?;
        let mut value = Vec::with_capacity(n);
        for k in 0..m {
            let target = read_uint(&ib[k * isize..], isize) as usize;
            if target >= count {
                return Err(AccessorFault::Invalid(format!("sparse index {k} is {target}, accessor count is {count}")));
            }
            value.clear();
            decode(&vb[k * elem..], &mut value);
            out[target * n..target * n + n].copy_from_slice(&value);
        }
    }
    Ok(out)
}

/// An unsigned little-endian integer of `size` bytes.
pub(crate) fn read_uint(b: &[u8], size: usize) -> u32 {
    match size {
        1 => b[0] as u32,
        2 => u16::from_le_bytes([b[0], b[1]]) as u32,
        _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
    }
}
