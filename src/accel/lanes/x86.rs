//! [`SphereLanes::closest_batch`](super::SphereLanes::closest_batch) written with x86 vector
//! intrinsics: the same arithmetic in the same order as the portable loop, so the same bits, but
//! with the closest distance and sphere of each ray held in registers from sphere to sphere.
//!
//! Why not leave it to the compiler: from the portable loop LLVM kept both in memory. It chose
//! the closer sphere's index by selecting between two addresses and gathering through them
//! (`vpgatherqq`, 4% of a cornell render's samples on the instruction after it), and stored the
//! closer distance with a masked store that the next sphere's full load could not forward from
//! (the AVX2 build: `vmaskmovpd`). Here both are blends between registers.

use std::arch::x86_64::*;

use super::{FlatSphere, RayBatch, LANES};

// A group is one AVX-512 vector of f64, or two AVX2 ones.
const _: () = assert!(LANES == 8);

/// Eight rays a vector. `batch` is prepared (its outputs sized to whole groups).
///
/// # Safety
/// The CPU must have AVX-512F.
#[target_feature(enable = "avx512f")]
pub(super) unsafe fn closest_batch_avx512(flat: &[FlatSphere], batch: &mut RayBatch) {
    let zero = _mm512_setzero_pd();
    let sign = _mm512_castpd_si512(_mm512_set1_pd(-0.0));
    let (groups, t, prim) = batch.split();
    for (g, (t, prim)) in groups
        .iter()
        .zip(t.chunks_exact_mut(LANES).zip(prim.chunks_exact_mut(LANES)))
    {
        // SAFETY (each load and store): every array and chunk here holds eight lanes.
        let ox = unsafe { _mm512_loadu_pd(g.ox.as_ptr()) };
        let oy = unsafe { _mm512_loadu_pd(g.oy.as_ptr()) };
        let oz = unsafe { _mm512_loadu_pd(g.oz.as_ptr()) };
        let dx = unsafe { _mm512_loadu_pd(g.dx.as_ptr()) };
        let dy = unsafe { _mm512_loadu_pd(g.dy.as_ptr()) };
        let dz = unsafe { _mm512_loadu_pd(g.dz.as_ptr()) };
        let mut best = unsafe { _mm512_loadu_pd(g.t_max.as_ptr()) };
        let mut best_prim = _mm512_set1_epi64(-1);
        for s in flat {
            let r2 = _mm512_set1_pd(s.r2);
            let fx = _mm512_sub_pd(ox, _mm512_set1_pd(s.cx));
            let fy = _mm512_sub_pd(oy, _mm512_set1_pd(s.cy));
            let fz = _mm512_sub_pd(oz, _mm512_set1_pd(s.cz));
            let b = _mm512_add_pd(
                _mm512_add_pd(_mm512_mul_pd(fx, dx), _mm512_mul_pd(fy, dy)),
                _mm512_mul_pd(fz, dz),
            );
            let lx = _mm512_sub_pd(fx, _mm512_mul_pd(dx, b));
            let ly = _mm512_sub_pd(fy, _mm512_mul_pd(dy, b));
            let lz = _mm512_sub_pd(fz, _mm512_mul_pd(dz, b));
            let l2 = _mm512_add_pd(
                _mm512_add_pd(_mm512_mul_pd(lx, lx), _mm512_mul_pd(ly, ly)),
                _mm512_mul_pd(lz, lz),
            );
            let disc = _mm512_sub_pd(r2, l2);
            let meets = _mm512_cmp_pd_mask::<_CMP_GE_OQ>(disc, zero);
            if meets == 0 {
                continue;
            }
            let f2 = _mm512_add_pd(
                _mm512_add_pd(_mm512_mul_pd(fx, fx), _mm512_mul_pd(fy, fy)),
                _mm512_mul_pd(fz, fz),
            );
            let c = _mm512_sub_pd(f2, r2);
            // disc.max(0.0): a NaN disc gives 0, as `vmaxpd` returns its second operand then.
            let root_disc = _mm512_castpd_si512(_mm512_sqrt_pd(_mm512_max_pd(disc, zero)));
            let b_bits = _mm512_castpd_si512(b);
            let signed = _mm512_castsi512_pd(_mm512_or_si512(
                _mm512_andnot_si512(sign, root_disc),
                _mm512_and_si512(sign, b_bits),
            ));
            let neg_b = _mm512_castsi512_pd(_mm512_xor_si512(b_bits, sign));
            let q = _mm512_sub_pd(neg_b, signed);
            let t0 = _mm512_div_pd(c, q);
            // t0.min(q) and t0.max(q): `vminpd`/`vmaxpd` return their second operand (t0) when
            // either is NaN; f64's min and max return q when t0 is NaN.
            let t0_nan = _mm512_cmp_pd_mask::<_CMP_UNORD_Q>(t0, t0);
            let lo = _mm512_mask_mov_pd(_mm512_min_pd(q, t0), t0_nan, q);
            let hi = _mm512_mask_mov_pd(_mm512_max_pd(q, t0), t0_nan, q);
            let root = _mm512_mask_mov_pd(hi, _mm512_cmp_pd_mask::<_CMP_GT_OQ>(lo, zero), lo);
            let closer = meets
                & _mm512_cmp_pd_mask::<_CMP_GT_OQ>(root, zero)
                & _mm512_cmp_pd_mask::<_CMP_LT_OQ>(root, best);
            best = _mm512_mask_mov_pd(best, closer, root);
            best_prim = _mm512_mask_mov_epi64(best_prim, closer, _mm512_set1_epi64(s.prim as i64));
        }
        unsafe { _mm512_storeu_pd(t.as_mut_ptr(), best) };
        // The low 32 bits of each index: u64::MAX becomes u32::MAX, "no hit".
        let prims = _mm512_cvtepi64_epi32(best_prim);
        unsafe { _mm256_storeu_si256(prim.as_mut_ptr().cast(), prims) };
    }
}

/// Four rays a vector, the same steps in AVX2 (written out again rather than behind a vector
/// trait: each line is its own instruction set's intrinsic, and where AVX-512 has mask registers
/// AVX2 has vector masks and `blendv`).
///
/// # Safety
/// The CPU must have AVX2.
#[target_feature(enable = "avx2")]
pub(super) unsafe fn closest_batch_avx2(flat: &[FlatSphere], batch: &mut RayBatch) {
    let zero = _mm256_setzero_pd();
    let sign = _mm256_set1_pd(-0.0);
    let (groups, t, prim) = batch.split();
    let halves = groups.iter().flat_map(|g| [(g, 0), (g, 4)]);
    for ((g, h), (t, prim)) in halves.zip(t.chunks_exact_mut(4).zip(prim.chunks_exact_mut(4))) {
        // SAFETY (each load and store): lanes h..h + 4 of eight, chunks of four.
        let ox = unsafe { _mm256_loadu_pd(g.ox.as_ptr().add(h)) };
        let oy = unsafe { _mm256_loadu_pd(g.oy.as_ptr().add(h)) };
        let oz = unsafe { _mm256_loadu_pd(g.oz.as_ptr().add(h)) };
        let dx = unsafe { _mm256_loadu_pd(g.dx.as_ptr().add(h)) };
        let dy = unsafe { _mm256_loadu_pd(g.dy.as_ptr().add(h)) };
        let dz = unsafe { _mm256_loadu_pd(g.dz.as_ptr().add(h)) };
        let mut best = unsafe { _mm256_loadu_pd(g.t_max.as_ptr().add(h)) };
        let mut best_prim = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
        for s in flat {
            let r2 = _mm256_set1_pd(s.r2);
            let fx = _mm256_sub_pd(ox, _mm256_set1_pd(s.cx));
            let fy = _mm256_sub_pd(oy, _mm256_set1_pd(s.cy));
            let fz = _mm256_sub_pd(oz, _mm256_set1_pd(s.cz));
            let b = _mm256_add_pd(
                _mm256_add_pd(_mm256_mul_pd(fx, dx), _mm256_mul_pd(fy, dy)),
                _mm256_mul_pd(fz, dz),
            );
            let lx = _mm256_sub_pd(fx, _mm256_mul_pd(dx, b));
            let ly = _mm256_sub_pd(fy, _mm256_mul_pd(dy, b));
            let lz = _mm256_sub_pd(fz, _mm256_mul_pd(dz, b));
            let l2 = _mm256_add_pd(
                _mm256_add_pd(_mm256_mul_pd(lx, lx), _mm256_mul_pd(ly, ly)),
                _mm256_mul_pd(lz, lz),
            );
            let disc = _mm256_sub_pd(r2, l2);
            let meets = _mm256_cmp_pd::<_CMP_GE_OQ>(disc, zero);
            if _mm256_movemask_pd(meets) == 0 {
                continue;
            }
            let f2 = _mm256_add_pd(
                _mm256_add_pd(_mm256_mul_pd(fx, fx), _mm256_mul_pd(fy, fy)),
                _mm256_mul_pd(fz, fz),
            );
            let c = _mm256_sub_pd(f2, r2);
            let root_disc = _mm256_sqrt_pd(_mm256_max_pd(disc, zero));
            let signed = _mm256_or_pd(_mm256_andnot_pd(sign, root_disc), _mm256_and_pd(sign, b));
            let q = _mm256_sub_pd(_mm256_xor_pd(b, sign), signed);
            let t0 = _mm256_div_pd(c, q);
            let t0_nan = _mm256_cmp_pd::<_CMP_UNORD_Q>(t0, t0);
            let lo = _mm256_blendv_pd(_mm256_min_pd(q, t0), q, t0_nan);
            let hi = _mm256_blendv_pd(_mm256_max_pd(q, t0), q, t0_nan);
            let root = _mm256_blendv_pd(hi, lo, _mm256_cmp_pd::<_CMP_GT_OQ>(lo, zero));
            let closer = _mm256_and_pd(
                meets,
                _mm256_and_pd(
                    _mm256_cmp_pd::<_CMP_GT_OQ>(root, zero),
                    _mm256_cmp_pd::<_CMP_LT_OQ>(root, best),
                ),
            );
            best = _mm256_blendv_pd(best, root, closer);
            let prim = _mm256_castsi256_pd(_mm256_set1_epi64x(s.prim as i64));
            best_prim = _mm256_blendv_pd(best_prim, prim, closer);
        }
        unsafe { _mm256_storeu_pd(t.as_mut_ptr(), best) };
        let mut prims = [0u64; 4];
        // SAFETY: `prims` holds four u64.
        unsafe { _mm256_storeu_si256(prims.as_mut_ptr().cast(), _mm256_castpd_si256(best_prim)) };
        for (out, p) in prim.iter_mut().zip(prims) {
            *out = p as u32;
        }
    }
}
