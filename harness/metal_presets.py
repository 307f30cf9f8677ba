"""Prints the RGB complex indices of refraction (eta, k) Mitsuba 3 gives its named conductors in
its RGB variants: its spectral data (mitsuba/data/ior/<name>.{eta,k}.spd) through its own
`spectrum_list_to_srgb` (ior.h, `ior_from_file`), read back from a `conductor` BSDF. ptui's
`material::metals` table is this script's output:

    target/mitsuba-venv/bin/python harness/metal_presets.py
"""
import mitsuba as mi

mi.set_variant("scalar_rgb")

# The elemental metals of Mitsuba's conductor-ior-list (without the Palik duplicates).
NAMES = ["Ag", "Al", "Au", "Be", "Cr", "Cu", "Hg", "Ir", "K", "Li", "Mo", "Nb", "Rh", "Ta",
         "V", "W"]

print(f"// Mitsuba {mi.__version__}, variant scalar_rgb")
for name in NAMES:
    try:
        bsdf = mi.load_dict({"type": "conductor", "material": name})
    except Exception:
        # A name Mitsuba has only under its Palik data (V).
        bsdf = mi.load_dict({"type": "conductor", "material": name + "_palik"})
        name_src = name + "_palik"
    else:
        name_src = name
    params = mi.traverse(bsdf)
    eta = [float(x) for x in params["eta.value"]]
    k = [float(x) for x in params["k.value"]]
    fmt = lambda v: ", ".join(f"{x:.6}" for x in v)
    print(f'    ("{name}", "{name_src}", [{fmt(eta)}], [{fmt(k)}]),')
