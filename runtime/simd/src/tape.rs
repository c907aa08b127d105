//! The tape of a dependence-split kernel (issue 24, `uplift_compiler::packet_split`): where a
//! kernel's group pass leaves the per-group values its point pass reads.
//!
//! A split kernel runs in two passes. The group pass computes, for a packet of `S::LANES`
//! groups (a group: one material and one view), every value that depends on the group only,
//! and stores those the point pass needs into numbered slots: slot `k` of the packet is
//! `tape[k·LANES .. (k+1)·LANES]`, lane `j` holding group `j`'s value (one contiguous store per
//! slot, [`put`]). The point pass then runs over the points of one group at a time — every lane
//! of its packets in that group — and reads slot `k` as a broadcast of the group's lane
//! ([`TapeRow::f`]: one scalar load and a splat). Integers travel as their bits, masks as
//! 1.0/0.0. Each callee of a split function has its own range of slots, reached through
//! [`TapeRow::at`] and a sub-slice in the group pass.

use crate::{I32s, M32s, Simd, U32s};

/// Stores `v` (one value per group of the packet) into slot `k` of a group pass's tape.
#[inline(always)]
pub fn put<S: Simd>(s: S, tape: &mut [f32], k: usize, v: S::F) {
    s.store(v, &mut tape[k * S::LANES..(k + 1) * S::LANES]);
}

/// [`put`] for an i32 packet (its bits).
#[inline(always)]
pub fn put_i<S: Simd>(s: S, tape: &mut [f32], k: usize, v: S::I) {
    put(s, tape, k, v.to_u32_bits().to_f32_bits());
}

/// [`put`] for a u32 packet (its bits).
#[inline(always)]
pub fn put_u<S: Simd>(s: S, tape: &mut [f32], k: usize, v: S::U) {
    put(s, tape, k, v.to_f32_bits());
}

/// [`put`] for a mask (1.0 where on).
#[inline(always)]
pub fn put_m<S: Simd>(s: S, tape: &mut [f32], k: usize, v: S::M) {
    put(s, tape, k, v.select(s.splat(1.0), s.splat(0.0)));
}

/// One group's view of a tape written by a group pass of `S::LANES`-wide packets (the same
/// level as the point pass that reads it): the group is lane `lane` of its packet.
#[derive(Clone, Copy, Debug)]
pub struct TapeRow<'a> {
    /// The tape from the group's lane of the current range's first slot on: slot `k` is at
    /// `k · S::LANES`.
    slots: &'a [f32],
}

impl<'a> TapeRow<'a> {
    /// The row of lane `lane` of a tape written `lanes` groups at a time.
    pub fn new(slots: &'a [f32], lanes: usize, lane: usize) -> Self {
        assert!(lane < lanes, "TapeRow: lane {lane} of a {lanes}-lane tape");
        TapeRow { slots: &slots[lane.min(slots.len())..] }
    }

    /// The row, checked once to hold `slots` slots (a split pass calls this on entry, so that
    /// its reads at constant slots need no bounds check of their own).
    #[inline(always)]
    pub fn fit<S: Simd>(self, slots: usize) -> Self {
        assert!(slots == 0 || self.slots.len() > (slots - 1) * S::LANES, "TapeRow: fewer than {slots} slots");
        self
    }

    /// The slots from `base` on (a callee's range).
    #[inline(always)]
    pub fn at<S: Simd>(self, base: usize) -> Self {
        TapeRow { slots: &self.slots[base * S::LANES..] }
    }

    /// Slot `k`, every lane the group's value.
    #[inline(always)]
    pub fn f<S: Simd>(self, s: S, k: usize) -> S::F {
        s.splat(self.slots[k * S::LANES])
    }

    /// Slot `k` as an i32 packet.
    #[inline(always)]
    pub fn i<S: Simd>(self, s: S, k: usize) -> S::I {
        s.splat_i(self.slots[k * S::LANES].to_bits() as i32)
    }

    /// Slot `k` as a u32 packet.
    #[inline(always)]
    pub fn u<S: Simd>(self, s: S, k: usize) -> S::U {
        s.splat_u(self.slots[k * S::LANES].to_bits())
    }

    /// Slot `k` as a mask.
    #[inline(always)]
    pub fn m<S: Simd>(self, s: S, k: usize) -> S::M {
        s.first_lanes(if self.slots[k * S::LANES] != 0.0 { usize::MAX } else { 0 })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Emu, F32s};

    #[test]
    fn every_kind_round_trips_through_a_slot() {
        let s = Emu::<4>;
        let mut tape = vec![0.0f32; 4 * 4];
        put(s, &mut tape, 0, s.load(&[1.5, -2.0, f32::INFINITY, 0.0]));
        put_i(s, &mut tape, 1, s.load_i(&[-7, i32::MIN, 0, 123_456_789]));
        put_u(s, &mut tape, 2, s.load_u(&[u32::MAX, 0x7fc0_0001, 1, 0]));
        put_m(s, &mut tape, 3, s.load(&[1.0, 0.0, -1.0, f32::NAN]).gt(s.splat(0.0)));
        let expect_i = [-7, i32::MIN, 0, 123_456_789];
        let expect_u = [u32::MAX, 0x7fc0_0001, 1, 0];
        for lane in 0..4 {
            let row = TapeRow::new(&tape, 4, lane).fit::<Emu<4>>(4);
            let mut f = [0.0f32; 4];
            row.f(s, 0).write_to(&mut f);
            assert_eq!(f[0].to_bits(), [1.5f32, -2.0, f32::INFINITY, 0.0][lane].to_bits());
            let mut i = [0i32; 4];
            row.i(s, 1).write_to(&mut i);
            assert_eq!(i, [expect_i[lane]; 4]);
            let mut u = [0u32; 4];
            row.u(s, 2).write_to(&mut u);
            assert_eq!(u, [expect_u[lane]; 4]);
            assert_eq!(row.m(s, 3).all(), lane == 0);
            assert_eq!(row.m(s, 3).any(), lane == 0);
            // A callee's range starts `base` slots in.
            let mut g = [0.0f32; 4];
            row.at::<Emu<4>>(1).f(s, 1).write_to(&mut g);
            assert_eq!(g[0].to_bits(), f32::from_bits(expect_u[lane]).to_bits());
        }
    }
}
