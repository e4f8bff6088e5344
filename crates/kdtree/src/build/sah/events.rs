//! The event lists of the SAH build: one `u64` key per event, sorted once at the root by a
//! radix sort and kept sorted by merging.

use raybench_geom::Aabb;

/// An event packed into one `u64` so sorting and merging compare integers: the position's
/// order-preserving bits (32), the kind (2), the triangle id (30). Sorting the keys sorts by
/// position, then kind (`END < PLANAR < START`), then triangle, which makes the build
/// deterministic.
pub(super) type Event = u64;

pub(super) const END: u64 = 0;
pub(super) const PLANAR: u64 = 1;
pub(super) const START: u64 = 2;
const TRI_MASK: u64 = (1 << 30) - 1;

/// `f32` to `u32` preserving order (negative values flipped); `-0` is first made `+0` so the
/// two zeros are one position, as they compare equal.
#[inline(always)]
pub(super) fn ord(x: f32) -> u32 {
    let b = (x + 0.0).to_bits();
    if b >> 31 == 1 { !b } else { b | 0x8000_0000 }
}

#[inline(always)]
pub(super) fn unord(u: u32) -> f32 {
    f32::from_bits(if u >> 31 == 1 { u & 0x7fff_ffff } else { !u })
}

#[inline(always)]
pub(super) fn event(pos: f32, kind: u64, tri: u32) -> Event {
    ((ord(pos) as u64) << 32) | (kind << 30) | tri as u64
}

#[inline(always)]
pub(super) fn pos_of(e: Event) -> u32 {
    (e >> 32) as u32
}

#[inline(always)]
pub(super) fn kind_of(e: Event) -> u64 {
    (e >> 30) & 3
}

#[inline(always)]
pub(super) fn tri_of(e: Event) -> u32 {
    (e & TRI_MASK) as u32
}

pub(super) type Events = [Vec<Event>; 3];

/// The events of one triangle whose bounds in the current cell are `b`.
pub(super) fn push_events(ev: &mut Events, b: &Aabb, tri: u32) {
    for (a, list) in ev.iter_mut().enumerate() {
        let (lo, hi) = (b.min[a], b.max[a]);
        if lo == hi {
            list.push(event(lo, PLANAR, tri));
        } else {
            list.push(event(lo, START, tri));
            list.push(event(hi, END, tri));
        }
    }
}

/// Sorts events pushed in increasing triangle order: a stable LSD radix sort on the 34 bits of
/// position and kind (three passes of 12, 11 and 11 bits), which leaves events with the same
/// position and kind in triangle order, i.e. sorts the whole `u64` keys. The one O(N log N)
/// sort of the build (measured: see docs/experiments.md, k-d tree, LSD radix sort).
pub(super) fn radix_sort(keys: &mut Vec<Event>) {
    let mut tmp = vec![0u64; keys.len()];
    for (shift, bits) in [(30u32, 12u32), (42, 11), (53, 11)] {
        let mask = (1u64 << bits) - 1;
        let mut offsets = vec![0usize; 1 << bits];
        for &k in keys.iter() {
            offsets[((k >> shift) & mask) as usize] += 1;
        }
        let mut sum = 0;
        for o in offsets.iter_mut() {
            let c = *o;
            *o = sum;
            sum += c;
        }
        for &k in keys.iter() {
            let d = ((k >> shift) & mask) as usize;
            tmp[offsets[d]] = k;
            offsets[d] += 1;
        }
        std::mem::swap(keys, &mut tmp);
    }
}

/// Merges the sorted `b` into the sorted `a`, in place from the back (no second buffer: `a`
/// usually has the room reserved already).
pub(super) fn merge_into(a: &mut Vec<Event>, b: &[Event]) {
    if b.is_empty() {
        return;
    }
    let (mut i, mut j) = (a.len(), b.len());
    a.resize(i + j, 0);
    let mut w = a.len();
    while j > 0 {
        w -= 1;
        if i > 0 && a[i - 1] > b[j - 1] {
            a[w] = a[i - 1];
            i -= 1;
        } else {
            a[w] = b[j - 1];
            j -= 1;
        }
    }
}
