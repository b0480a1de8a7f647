//! [`Ray`] and [`Hit`], the records every crate passes around (and the ray and hit files
//! store, field for field: see [`crate::rays`]).

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// One ray; the field order is the file's record order.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct Ray {
    pub origin: [f32; 3],
    pub tmin: f32,
    pub dir: [f32; 3],
    pub tmax: f32,
}

impl Ray {
    pub fn new(origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Ray {
        Ray { origin: origin.to_array(), tmin, dir: dir.to_array(), tmax }
    }
    pub fn o(&self) -> Vec3 {
        Vec3::from_array(self.origin)
    }
    pub fn d(&self) -> Vec3 {
        Vec3::from_array(self.dir)
    }
    pub fn at(&self, t: f32) -> Vec3 {
        self.o() + self.d() * t
    }
    /// The same ray with its segment ending at `t` (never before `tmin`).
    pub fn ending_at(&self, t: f32) -> Ray {
        Ray { tmax: t.max(self.tmin), ..*self }
    }
}

/// Triangle index that marks a miss.
pub const NO_HIT: u32 = u32::MAX;

/// Closest hit of one ray; the field order is the file's record order.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct Hit {
    pub t: f32,
    pub triangle: u32,
    pub u: f32,
    pub v: f32,
}

impl Hit {
    pub const MISS: Hit = Hit { t: f32::INFINITY, triangle: NO_HIT, u: 0.0, v: 0.0 };

    pub fn is_hit(&self) -> bool {
        self.triangle != NO_HIT
    }

    /// Bitwise equality (distinguishes -0.0 from 0.0; NaN never appears in a hit).
    pub fn same_bits(&self, other: &Hit) -> bool {
        bytemuck::bytes_of(self) == bytemuck::bytes_of(other)
    }
}
