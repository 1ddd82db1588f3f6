//! [`SetOps`]: composition and converse of *sets* of base relations by table lookup over bit
//! blocks — the kernel of binary path consistency.
//!
//! ## Why blocks
//! Closure composes sets, not base relations: `R ∘ S = ⋃ r ∘ s` over `r ∈ R, s ∈ S`. Done
//! pair by pair that is `|R|·|S|` unions (up to 400 for OPRA-1, 5,184 for OPRA-2). Cut each
//! set into blocks of `b` bits and precompute, for every pair of blocks and every pair of
//! their values, the union of the compositions of the relations they hold: then `R ∘ S` is one
//! union per pair of non-empty blocks. With `b = 8` a calculus of ≤ 8 relations (RCC-8, the
//! point algebra) composes any two sets in *one* lookup, as GQR does; Allen's 13 relations and
//! OPRA-1's 20 take at most 4 and 9. `b` is the largest of 8, 4, 2, 1 whose table fits in
//! [`MAX_BLOCK_TABLE_BYTES`]; `b = 1` is the base table itself.
//!
//! ## Early exit
//! Closure only needs to know whether `T ∩ (R ∘ S)` is smaller than `T`. The union grows
//! block by block and stops once it covers `T`. Two shortcuts skip the lookups altogether
//! when one side is universal (an edge nothing constrains — most of a sparse network): if
//! some `r ∈ R` has `r ∘ U = U`, then `R ∘ U = U` refines nothing.

use crate::calculus::StateId;
use crate::compose::ComposeTable;

/// The most memory the block composition table may take.
pub(crate) const MAX_BLOCK_TABLE_BYTES: usize = 8 << 20;

/// Up to this many blocks per set, composition looks up every pair of blocks without
/// branching; beyond, only the non-empty ones, stopping once the target is covered.
const DENSE_BLOCKS: usize = 3;

/// The word counts closure is compiled for; a set is padded to the next one.
pub(crate) const WORD_SIZES: [usize; 11] = [1, 2, 3, 4, 5, 6, 8, 12, 16, 24, 32];

/// Set composition and converse by block tables (see the module docs).
#[derive(Debug)]
pub(crate) struct SetOps {
    /// Words per set, padded to one of [`WORD_SIZES`].
    words: usize,
    /// Bits per block (8, 4, 2 or 1, which divide 64, so no block straddles two words; or the
    /// number of relations when that is below 8 — one block in one word).
    block: usize,
    n_blocks: usize,
    /// `compose[(((kl · V + vl) · nb + kr) · V + vr) · words ..]`, `V = 2^b` (value 0: empty).
    compose: Vec<u64>,
    /// `compose` as 16-bit entries, for calculi of at most 16 relations (empty otherwise):
    /// the same lookups from a table a quarter the size, which stays in a core's cache (RCC-8:
    /// 128 KB rather than 512 KB; Allen: 128 KB rather than 512 KB).
    compact: Vec<u16>,
    /// `converse[(k · V + v) · words ..]`.
    converse: Vec<u64>,
    /// `base[(r · n + s) · words ..]`: `r ∘ s` of two base relations (a small table a
    /// composition of two single relations reads instead of the block table).
    base: Vec<u64>,
    n_states: usize,
    universal: Vec<u64>,
    /// Relations `r` with `r ∘ U = U`.
    left_total: Vec<u64>,
    /// Relations `s` with `U ∘ s = U`.
    right_total: Vec<u64>,
    /// Whether `U ∘ U = U` (then an edge nothing constrains need not start in the queue).
    universal_closed: bool,
    /// Weight of each base relation.
    weights: Vec<u32>,
    /// For few blocks ([`DENSE_BLOCKS`]): per base relation `s`, the blocks of every left set
    /// composed with `s` alone — `by_right[((s · nb + kl) · V + vl) · words ..]` — the block
    /// table's entries for a fixed single right input, gathered from `compose`'s stride so a
    /// closure composing many left sets with one single right set reads them in order.
    by_right: Vec<u64>,
}

fn set_bit(words: &mut [u64], i: usize) {
    words[i / 64] |= 1 << (i % 64);
}

fn or_into(dst: &mut [u64], src: &[u64]) {
    for (d, s) in dst.iter_mut().zip(src) {
        *d |= s;
    }
}

impl SetOps {
    pub(crate) fn new(table: &ComposeTable, converse: &[Vec<StateId>], weights: &[u32]) -> Self {
        let n = table.n_states();
        let exact = n.div_ceil(64).max(1);
        let words = WORD_SIZES
            .iter()
            .copied()
            .find(|&w| w >= exact)
            .unwrap_or(exact);
        let fits = |b: usize| {
            let nb = n.div_ceil(b);
            let v = 1usize << b;
            nb * nb * v * v * words * 8 <= MAX_BLOCK_TABLE_BYTES
        };
        // A calculus of fewer than 8 relations is one block of exactly its size; one of 9 to 16
        // relations two equal blocks (Allen's 13: 7 + 6 bits, a 0.5 MB table rather than the
        // 2 MB of 8 + 5 that falls out of a core's cache — GQR's "Hogge's method" splits the
        // same way). Both stay within one word.
        let block = if (9..=16).contains(&n) {
            n.div_ceil(2)
        } else {
            [8, 4, 2]
                .into_iter()
                .find(|&b| fits(b))
                .unwrap_or(1)
                .min(n.max(1))
        };
        let n_blocks = n.div_ceil(block);
        let v_count = 1usize << block;
        let id = |i: usize| StateId(u16::try_from(i).unwrap_or(u16::MAX));
        // Base compositions as words.
        let mut base = vec![0u64; n * n * words];
        for r in 0..n {
            for s in 0..n {
                let at = (r * n + s) * words;
                for t in table.get(id(r), id(s)) {
                    set_bit(&mut base[at..at + words], t.index());
                }
            }
        }
        let relation = |k: usize, v: usize| k * block + v.trailing_zeros() as usize;
        let mut compose = vec![0u64; n_blocks * v_count * n_blocks * v_count * words];
        let at = |kl: usize, vl: usize, kr: usize, vr: usize| {
            (((kl * v_count + vl) * n_blocks + kr) * v_count + vr) * words
        };
        let mut tmp = vec![0u64; words];
        for kl in 0..n_blocks {
            for kr in 0..n_blocks {
                // Values with bits past the last relation never occur in a set.
                let (wl, wr) = ((n - kl * block).min(block), (n - kr * block).min(block));
                for vl in 1..1usize << wl {
                    for vr in 1..1usize << wr {
                        let (r, s) = (relation(kl, vl), relation(kr, vr));
                        let (lo_l, lo_r) = (vl & vl.wrapping_neg(), vr & vr.wrapping_neg());
                        if vl != lo_l {
                            // Union of the lowest relation's row and the rest's (both done).
                            tmp.copy_from_slice(&compose[at(kl, lo_l, kr, vr)..][..words]);
                            or_into(&mut tmp, &compose[at(kl, vl ^ lo_l, kr, vr)..][..words]);
                        } else if vr != lo_r {
                            tmp.copy_from_slice(&compose[at(kl, vl, kr, lo_r)..][..words]);
                            or_into(&mut tmp, &compose[at(kl, vl, kr, vr ^ lo_r)..][..words]);
                        } else {
                            tmp.copy_from_slice(&base[(r * n + s) * words..][..words]);
                        }
                        compose[at(kl, vl, kr, vr)..][..words].copy_from_slice(&tmp);
                    }
                }
            }
        }
        let mut by_right = Vec::new();
        if n_blocks <= DENSE_BLOCKS {
            by_right = vec![0u64; n * n_blocks * v_count * words];
            for s in 0..n {
                let (kr, vr) = (s / block, 1usize << (s % block));
                for kl in 0..n_blocks {
                    for vl in 0..v_count {
                        let to = ((s * n_blocks + kl) * v_count + vl) * words;
                        by_right[to..to + words]
                            .copy_from_slice(&compose[at(kl, vl, kr, vr)..][..words]);
                    }
                }
            }
        }
        let mut conv = vec![0u64; n_blocks * v_count * words];
        for k in 0..n_blocks {
            for v in 1..v_count {
                let at = (k * v_count + v) * words;
                for bit in 0..block {
                    let r = k * block + bit;
                    if v & (1 << bit) != 0 && r < n {
                        for t in &converse[r] {
                            set_bit(&mut conv[at..at + words], t.index());
                        }
                    }
                }
            }
        }
        let mut universal = vec![0u64; words];
        crate::reason::fill_universal(&mut universal, n);
        let mut left_total = vec![0u64; words];
        let mut right_total = vec![0u64; words];
        let mut any = vec![0u64; words];
        for r in 0..n {
            let (mut row, mut col) = (vec![0u64; words], vec![0u64; words]);
            for s in 0..n {
                or_into(&mut row, &base[(r * n + s) * words..][..words]);
                or_into(&mut col, &base[(s * n + r) * words..][..words]);
            }
            or_into(&mut any, &row);
            if row == universal {
                set_bit(&mut left_total, r);
            }
            if col == universal {
                set_bit(&mut right_total, r);
            }
        }
        let compact = if n <= 16 && words == 1 {
            // Every entry is a set of at most 16 relations in the low bits of one word.
            compose.iter().map(|&w| (w & 0xffff) as u16).collect()
        } else {
            Vec::new()
        };
        Self {
            base,
            n_states: n,
            words,
            block,
            n_blocks,
            compose,
            compact,
            converse: conv,
            universal_closed: any == universal,
            universal,
            left_total,
            right_total,
            weights: weights.to_vec(),
            by_right,
        }
    }

    /// Words per set (padded).
    pub(crate) fn words(&self) -> usize {
        self.words
    }

    /// Whether `U ∘ U = U`.
    pub(crate) fn universal_closed(&self) -> bool {
        self.universal_closed
    }

    /// The kernel with the word count fixed at compile time.
    pub(crate) fn view<const W: usize>(&self) -> Option<SetView<'_, W>> {
        if W != self.words {
            return None;
        }
        let (compose, _) = self.compose.as_chunks::<W>();
        let (converse, _) = self.converse.as_chunks::<W>();
        let (base, _) = self.base.as_chunks::<W>();
        let (by_right, _) = self.by_right.as_chunks::<W>();
        let one = |v: &[u64]| -> Option<[u64; W]> { v.try_into().ok() };
        Some(SetView {
            block: self.block,
            n_blocks: self.n_blocks,
            v_count: 1usize << self.block,
            mask: if self.block == 64 {
                u64::MAX
            } else {
                (1u64 << self.block) - 1
            },
            compose,
            compact: &self.compact,
            converse,
            base,
            by_right,
            n_states: self.n_states,
            universal: one(&self.universal)?,
            left_total: one(&self.left_total)?,
            right_total: one(&self.right_total)?,
            weights: &self.weights,
            unit_weights: self.weights.iter().all(|w| *w == 1),
        })
    }
}

/// [`SetOps`] with sets as `[u64; W]`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SetView<'a, const W: usize> {
    block: usize,
    n_blocks: usize,
    v_count: usize,
    mask: u64,
    compose: &'a [[u64; W]],
    compact: &'a [u16],
    converse: &'a [[u64; W]],
    base: &'a [[u64; W]],
    by_right: &'a [[u64; W]],
    n_states: usize,
    pub(crate) universal: [u64; W],
    left_total: [u64; W],
    right_total: [u64; W],
    pub(crate) weights: &'a [u32],
    unit_weights: bool,
}

/// `x ∪ y`.
#[inline]
fn or<const W: usize>(x: &[u64; W], y: &[u64; W]) -> [u64; W] {
    std::array::from_fn(|i| x[i] | y[i])
}

/// Calls `f(block, value)` for each non-empty block of `set`.
#[inline]
fn for_blocks<const W: usize>(
    set: &[u64; W],
    block: usize,
    mask: u64,
    mut f: impl FnMut(usize, usize) -> bool,
) -> bool {
    let per_word = 64 / block;
    for (i, &w) in set.iter().enumerate() {
        let mut w = w;
        while w != 0 {
            let bit = w.trailing_zeros() as usize;
            let k = bit / block;
            let shift = k * block;
            let v = (w >> shift) & mask;
            w &= !(mask << shift);
            if !f(i * per_word + k, v as usize) {
                return false;
            }
        }
    }
    true
}

/// The relation of a set holding exactly one.
#[inline]
pub(crate) fn single<const W: usize>(set: &[u64; W]) -> Option<usize> {
    let mut found = None;
    for (i, &w) in set.iter().enumerate() {
        if w != 0 {
            if found.is_some() || w & (w - 1) != 0 {
                return None;
            }
            found = Some(i * 64 + w.trailing_zeros() as usize);
        }
    }
    found
}

#[inline]
fn meets<const W: usize>(a: &[u64; W], b: &[u64; W]) -> bool {
    a.iter().zip(b).any(|(x, y)| x & y != 0)
}

/// Whether `a ⊇ b`.
#[inline]
pub(crate) fn covers<const W: usize>(a: &[u64; W], b: &[u64; W]) -> bool {
    a.iter().zip(b).all(|(x, y)| y & !x == 0)
}

/// `left ∘ right` of two one-word sets by the compact table of `NB` blocks of `B` bits
/// ([`SetView::compact_layout`]), `table` cut to its `(NB·2^B)²` entries: with the layout
/// known at compile time the shifts, masks and offsets are constants and no lookup is
/// bounds-checked — GQR's one lookup for 8 relations, four for 16.
#[inline(always)]
pub(crate) fn compose_compact<const NB: usize, const B: usize>(
    table: &[u16],
    left: u64,
    right: u64,
) -> u64 {
    let mask = (1u64 << B) - 1;
    let at = |kl: usize, vl: u64, kr: usize, vr: u64| {
        ((((kl << B) | vl as usize) * NB + kr) << B) | vr as usize
    };
    let (l0, r0) = (left & mask, right & mask);
    let mut acc = u64::from(table[at(0, l0, 0, r0)]);
    if NB == 2 {
        let (l1, r1) = ((left >> B) & mask, (right >> B) & mask);
        acc |= u64::from(table[at(1, l1, 0, r0)])
            | u64::from(table[at(0, l0, 1, r1)])
            | u64::from(table[at(1, l1, 1, r1)]);
    }
    acc
}

impl<'a, const W: usize> SetView<'a, W> {
    /// `target ∩ (left ∘ right)` when that is strictly smaller than `target`, else `None`.
    /// Always inlined: a call per revision, with the sets passed through memory, cost binary
    /// closure a third of its time.
    #[inline(always)]
    pub(crate) fn refine(
        &self,
        left: &[u64; W],
        right: &[u64; W],
        target: &[u64; W],
    ) -> Option<[u64; W]> {
        let acc = self.composition_refining(left, right, target)?;
        let mut out = *target;
        for (o, a) in out.iter_mut().zip(&acc) {
            *o &= a;
        }
        Some(out)
    }

    /// `left ∘ right` when it misses part of `target` (so `target` can be refined), else
    /// `None` — found without finishing the union once it covers `target`. Always inlined:
    /// it is the body of both closures' innermost loops.
    #[inline(always)]
    pub(crate) fn composition_refining(
        &self,
        left: &[u64; W],
        right: &[u64; W],
        target: &[u64; W],
    ) -> Option<[u64; W]> {
        let (nb, vc) = (self.n_blocks, self.v_count);
        if W == 1 && nb <= 2 && !self.compact.is_empty() {
            // At most 16 relations in one or two blocks: the compact table, first (GQR's layout
            // for 16 relations; one lookup for 8) — no shortcut below is cheaper.
            let (l, r) = (left[0], right[0]);
            let (b, m) = (self.block, self.mask);
            let look = |kl: usize, vl: u64, kr: usize, vr: u64| {
                u64::from(self.compact[((kl * vc + vl as usize) * nb + kr) * vc + vr as usize])
            };
            let mut a = look(0, l & m, 0, r & m);
            if nb == 2 {
                let (lh, rh) = ((l >> b) & m, (r >> b) & m);
                a |= look(1, lh, 0, r & m) | look(0, l & m, 1, rh) | look(1, lh, 1, rh);
            }
            let acc: [u64; W] = std::array::from_fn(|_| a);
            return (!covers(&acc, target)).then_some(acc);
        }
        if let (Some(r), Some(s)) = (single(left), single(right)) {
            // Two single relations (a scenario's sets, a map's most likely states): the base
            // table, a few KiB that stay in cache.
            let acc = self.base[r * self.n_states + s];
            return (!covers(&acc, target)).then_some(acc);
        }
        if (*right == self.universal && meets(left, &self.left_total))
            || (*left == self.universal && meets(right, &self.right_total))
        {
            return None;
        }
        let mut acc = [0u64; W];
        if nb <= DENSE_BLOCKS {
            // Few blocks: every pair looked up, empty ones included (their entry is empty),
            // with no branch — GQR's "Hogge's method" for Allen's 13 relations is this with
            // two blocks.
            let value = |set: &[u64; W], k: usize| {
                let bit = k * self.block;
                ((set[bit / 64] >> (bit % 64)) & self.mask) as usize
            };
            for kl in 0..nb {
                let base = (kl * vc + value(left, kl)) * nb;
                for kr in 0..nb {
                    let row = &self.compose[(base + kr) * vc + value(right, kr)];
                    for (a, r) in acc.iter_mut().zip(row) {
                        *a |= r;
                    }
                }
            }
            return (!covers(&acc, target)).then_some(acc);
        }
        let covered = !for_blocks(left, self.block, self.mask, |kl, vl| {
            let base = (kl * vc + vl) * nb;
            for_blocks(right, self.block, self.mask, |kr, vr| {
                let row = &self.compose[(base + kr) * vc + vr];
                for (a, r) in acc.iter_mut().zip(row) {
                    *a |= r;
                }
                true
            });
            // Stop once the union covers the target: nothing can be removed.
            !covers(&acc, target)
        });
        (!covered && !covers(&acc, target)).then_some(acc)
    }

    /// Whether `U ∘ X = U` for every non-empty `X` (every relation `s` has `U ∘ s = U`): a
    /// rule whose left input is universal then refines nothing.
    pub(crate) fn universal_absorbs_from_left(&self) -> bool {
        self.right_total == self.universal
    }

    /// Whether `X ∘ U = U` for every non-empty `X`: a rule whose right input is universal
    /// then refines nothing.
    pub(crate) fn universal_absorbs_from_right(&self) -> bool {
        self.left_total == self.universal
    }

    /// With few blocks, the block table's entries for the left set `left` fixed: `left ∘ X`
    /// for any set `X` is the union of one entry per block of `X` ([`Self::through_word`]). A set
    /// within one block (every single relation) is a slice of the block table; one spanning
    /// blocks is the union of theirs, written to `buf` (at most [`DENSE_BLOCKS`] slices).
    /// `None` with many blocks.
    pub(crate) fn fixed_left<'b>(
        &'b self,
        left: &[u64; W],
        buf: &'b mut Vec<[u64; W]>,
    ) -> Option<&'b [[u64; W]]> {
        let (nb, vc) = (self.n_blocks, self.v_count);
        if nb > DENSE_BLOCKS {
            return None;
        }
        let region = |k: usize| {
            let bit = k * self.block;
            let v = ((left[bit / 64] >> (bit % 64)) & self.mask) as usize;
            (v != 0).then(|| &self.compose[(k * vc + v) * nb * vc..][..nb * vc])
        };
        let mut regions = (0..nb).filter_map(region);
        let first = regions.next()?;
        let Some(second) = regions.next() else {
            return Some(first);
        };
        buf.clear();
        buf.extend(first.iter().zip(second).map(|(x, y)| or(x, y)));
        for r in regions {
            for (d, x) in buf.iter_mut().zip(r) {
                *d = or(d, x);
            }
        }
        Some(buf)
    }

    /// As [`Self::fixed_left`] for the right set `right` fixed (`X ∘ right` through
    /// [`Self::through_word`]): the union of its relations' gathered entries, when it has at most
    /// `max_relations` (each costs a pass over the entries); `None` otherwise.
    pub(crate) fn fixed_right<'b>(
        &'b self,
        right: &[u64; W],
        max_relations: usize,
        buf: &'b mut Vec<[u64; W]>,
    ) -> Option<&'b [[u64; W]]> {
        let (nb, vc) = (self.n_blocks, self.v_count);
        if nb > DENSE_BLOCKS || self.by_right.is_empty() {
            return None;
        }
        let count: u32 = right.iter().map(|w| w.count_ones()).sum();
        if count == 0 || count as usize > max_relations {
            return None;
        }
        let mut states = crate::reason::iter_bits(right).map(|s| s.index());
        let entries = |s: usize| &self.by_right[s * nb * vc..][..nb * vc];
        let first = entries(states.next()?);
        if count == 1 {
            return Some(first);
        }
        buf.clear();
        buf.extend_from_slice(first);
        for s in states {
            for (d, x) in buf.iter_mut().zip(entries(s)) {
                *d = or(d, x);
            }
        }
        Some(buf)
    }

    /// For one-word sets of at most 16 relations: the compact table's blocks and bits per
    /// block, and the table (see [`compose_compact`]).
    pub(crate) fn compact_layout(&self) -> Option<(usize, usize, &'a [u16])> {
        (W == 1 && self.n_blocks <= 2 && !self.compact.is_empty()).then_some((
            self.n_blocks,
            self.block,
            self.compact,
        ))
    }

    /// Blocks per set.
    pub(crate) fn n_blocks(&self) -> usize {
        self.n_blocks
    }

    /// Bits per block.
    pub(crate) fn block(&self) -> usize {
        self.block
    }

    /// The composition of a one-word set with the single relation whose gathered entries
    /// `entries` are (from [`Self::fixed_left`] or [`Self::fixed_right`]): one lookup per block,
    /// no branch. The block count `NB` is known at compile time, and the block width `B` too
    /// when it is not 0 (then the shifts and table offsets are constants, and a caller that
    /// checked `entries.len() >= NB << B` has no bounds check left): the loops of ternary
    /// closure are instantiated per layout, so a row of the network is a straight pass.
    #[inline(always)]
    pub(crate) fn through_word<const NB: usize, const B: usize>(
        &self,
        entries: &[[u64; W]],
        set: u64,
    ) -> u64 {
        let mut acc = 0;
        for k in 0..NB {
            let v = if B == 0 {
                ((set >> (k * self.block)) & self.mask) as usize
            } else {
                ((set >> (k * B)) & ((1 << B) - 1)) as usize
            };
            let at = if B == 0 { k * self.v_count } else { k << B };
            acc |= entries[at + v][0];
        }
        acc
    }

    /// The weight of a set: the sum of its relations' weights (GQR's queue key).
    #[inline]
    pub(crate) fn weight(&self, set: &[u64; W]) -> u32 {
        if self.unit_weights {
            return set.iter().map(|w| w.count_ones()).sum();
        }
        crate::reason::iter_bits(set)
            .map(|r| self.weights[r.index()])
            .fold(0u32, u32::saturating_add)
    }

    /// The converse of a set.
    #[inline]
    pub(crate) fn converse(&self, set: &[u64; W]) -> [u64; W] {
        if W == 1 && self.n_blocks <= 2 {
            // One word, one or two blocks: a lookup per block, no loop (every revision puts
            // a set and its converse).
            let (b, m, vc) = (self.block, self.mask, self.v_count);
            let lo = self.converse[(set[0] & m) as usize];
            if self.n_blocks == 1 {
                return lo;
            }
            let hi = self.converse[vc + ((set[0] >> b) & m) as usize];
            return std::array::from_fn(|k| lo[k] | hi[k]);
        }
        let mut out = [0u64; W];
        for_blocks(set, self.block, self.mask, |k, v| {
            for (o, c) in out.iter_mut().zip(&self.converse[k * self.v_count + v]) {
                *o |= c;
            }
            true
        });
        out
    }
}
