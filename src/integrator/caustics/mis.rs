//! The ratio of path densities by which the joins and the camera paths share a caustic seen
//! after a bounce, and its light side carried along a light path.

/// The light side of [`connection_ratio`] along a light path: the start's density, the cosine
/// products of the specular chains, and at the first diffuse vertex y the turn towards the
/// chain to the second one.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LightSide {
    /// The start's density (emitter pmf x area pdf x direction pdf); after y, times what the
    /// first chain and y contribute.
    p: f64,
    cos0: f64,
    /// Product over the current chain's specular vertices of cos(arrival) / cos(departure), as
    /// seen from the light.
    chain_cos: f64,
    past_y: bool,
}

impl LightSide {
    pub(crate) fn new(p_start: f64, cos0: f64) -> Self {
        LightSide {
            p: p_start,
            cos0,
            chain_cos: 1.0,
            past_y: false,
        }
    }

    /// A specular bounce, its cosines on the light's way in and out.
    pub(crate) fn specular(&mut self, cos_arrival: f64, cos_departure: f64) {
        self.chain_cos *= cos_arrival / cos_departure;
    }

    /// Whether the path has left its first diffuse vertex y.
    pub(crate) fn past_y(&self) -> bool {
        self.past_y
    }

    /// The ratio's light side for a join to the diffuse vertex the path has reached.
    pub(crate) fn here(&self) -> f64 {
        if self.past_y {
            self.p * self.chain_cos
        } else {
            self.p * self.chain_cos / self.cos0
        }
    }

    /// Leaving y along a direction sampled with `pdf` (`reverse` the other way, as a camera
    /// path samples it): the join to the next diffuse vertex is weighed against the camera path
    /// that samples y's bounce towards the light's chain, so the light side takes y's forward
    /// over reverse pdf and the cosines of the two chains at y; the next chain starts its own
    /// cosine product.
    pub(crate) fn leave_y(&mut self, cos_in: f64, pdf: f64, reverse: f64, cos_out: f64) {
        let turn = cos_in * pdf / (reverse * cos_out);
        self.p *= self.chain_cos / self.cos0 * turn;
        self.chain_cos = 1.0;
        self.past_y = true;
    }
}

/// The same holds for the light path's second diffuse vertex x' (light -> chain -> y -> chain' ->
/// x'), joined to a camera vertex x: the camera path samples x', then x' towards the chain', then
/// y towards the light's chain, where the light path sampled y's bounce the other way. With
/// everything not at y as above, the light side gains y's forward over reverse pdf and the
/// cosines of the two chains at y ([`LightSide::leave_y`]), and K' of the chain': the camera
/// side has the same form, with x' in y's place (`path::Chains`).
///
/// The ratio p_connect / p_camera of the densities with which the two strategies produce the
/// path camera .. x -> y -> specular chain s_1 .. s_k -> light z: the light tracer's (its start,
/// the chain, then x joined to y) over the camera path's (x's BSDF towards y, y's BSDF along the
/// chain, landing on the light). In area measure the chain's segment lengths and Fresnel
/// choices appear in both and cancel, as does x's prefix; what is left is
///
///   r = p_start cos_y_in K / (pdf_x (cos_y_x / d_xy^2) pdf_y cos_z),
///
/// with cos_y_in the angle at y of the chain's last segment, cos_z that at the light of its
/// first, and K the product over specular vertices of cos(arrival) / cos(departure) seen from
/// the light (1 for a mirror; for a pass through a glass sphere the two interfaces cancel).
/// The light side's factors are `p_light` (p_start K / cos_z, [`CausticVertex::p_light`]); the
/// camera side's are `camera` (pdf_x cos_y_x / d_xy^2 pdf_y / cos_y_in, over K). Russian
/// roulette is left out of both, which keeps the weights summing to 1 (all MIS needs).
///
/// [`CausticVertex::p_light`]: super::CausticVertex::p_light
#[inline]
pub fn connection_ratio(p_light: f64, camera: f64) -> f64 {
    if camera > 0.0 {
        p_light / camera
    } else {
        f64::INFINITY
    }
}
