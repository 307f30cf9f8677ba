//! Named conductors for `metal = "Au"`: RGB complex indices of refraction (eta, k) relative to
//! air, exactly those Mitsuba 3 gives the same names in its RGB variants (its spectral data,
//! `data/ior/<name>.{eta,k}.spd`, integrated to sRGB by its `spectrum_list_to_srgb`), read out of
//! Mitsuba 3.9.1 by `harness/metal_presets.py`. So a ptui scene and a Mitsuba scene naming the
//! same metal render the same colour.

use crate::math::DVec3;

/// (name, eta, k), red, green, blue.
const METALS: [(&str, [f64; 3], [f64; 3]); 16] = [
    (
        "Ag",
        [0.155276, 0.116728, 0.138388],
        [4.82835, 3.12222, 2.1469],
    ),
    ("Al", [1.6575, 0.880405, 0.521244], [9.22381, 6.2695, 4.837]),
    (
        "Au",
        [0.143036, 0.375307, 1.44205],
        [3.983, 2.38556, 1.60336],
    ),
    (
        "Be",
        [4.18501, 3.18503, 2.78406],
        [3.83547, 3.01012, 2.86899],
    ),
    ("Cr", [4.36967, 2.91651, 1.6549], [5.20655, 4.23131, 3.7547]),
    (
        "Cu",
        [0.201005, 0.92375, 1.10222],
        [3.91326, 2.45305, 2.14209],
    ),
    (
        "Hg",
        [2.39894, 1.44003, 0.90957],
        [6.32759, 4.37192, 3.42176],
    ),
    (
        "Ir",
        [3.0863, 2.08219, 1.61791],
        [5.59215, 4.06709, 3.26731],
    ),
    (
        "K",
        [0.0640432, 0.0464098, 0.0381849],
        [2.1042, 1.34894, 0.913126],
    ),
    (
        "Li",
        [0.265791, 0.195618, 0.220949],
        [3.54015, 2.31112, 1.66861],
    ),
    (
        "Mo",
        [4.48397, 3.52513, 2.77631],
        [4.11144, 3.42083, 3.15061],
    ),
    (
        "Nb",
        [3.42007, 2.79009, 2.39563],
        [3.44139, 2.73767, 2.57975],
    ),
    (
        "Rh",
        [2.58579, 1.86022, 1.55426],
        [6.78226, 4.70299, 3.97607],
    ),
    (
        "Ta",
        [2.06272, 2.39294, 2.62793],
        [2.40836, 1.74149, 1.94703],
    ),
    // Mitsuba has vanadium only under Palik's data (`V_palik`).
    ("V", [4.27758, 3.51295, 2.76107], [3.4913, 2.88945, 3.11152]),
    (
        "W",
        [4.37082, 3.30025, 2.99841],
        [3.50064, 2.60487, 2.27323],
    ),
];

/// The (eta, k) of a named metal, or None for a name not in the table.
pub fn lookup(name: &str) -> Option<(DVec3, DVec3)> {
    METALS
        .iter()
        .find(|(n, _, _)| *n == name)
        .map(|(_, eta, k)| (DVec3::from_array(*eta), DVec3::from_array(*k)))
}

/// Every name, for error messages and the docs.
pub fn names() -> impl Iterator<Item = &'static str> {
    METALS.iter().map(|(n, _, _)| *n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::fresnel;

    /// Normal-incidence reflectances from the table against published values (Mitsuba's RGB
    /// integration of the same spectra): gold is red-yellow, silver and aluminium nearly white,
    /// copper red. A transposed row or swapped eta/k fails these.
    #[test]
    fn the_metals_have_their_colours() {
        let r = |name: &str| {
            let (eta, k) = lookup(name).expect("in the table");
            fresnel::conductor(1.0, eta, k)
        };
        let au = r("Au");
        assert!(au.x > 0.9 && au.y > 0.7 && au.z < 0.5, "gold {au:?}");
        let ag = r("Ag");
        assert!(ag.min_element() > 0.9, "silver {ag:?}");
        let al = r("Al");
        assert!(al.min_element() > 0.85, "aluminium {al:?}");
        let cu = r("Cu");
        assert!(cu.x > 0.9 && cu.z < 0.7 && cu.x > cu.y, "copper {cu:?}");
        assert!(lookup("Unobtainium").is_none());
        assert_eq!(names().count(), 16);
    }
}
