//! Writes the scenes of `scenes/extreme/` that are transformations of the built-in ones
//! (translated, scaled, huge walls, index-matched glass, tiny lights), so their numbers are exact
//! transformations rather than hand-typed. `tests/extreme_files.rs` checks the committed files
//! are what this program writes.
//!
//! ```sh
//! cargo xtask gen-extreme                # rewrite scenes/extreme/
//! cargo xtask gen-extreme --probe /tmp/p # write the beyond-the-limit variants used to find
//!                                        # where it breaks there instead
//! ```

use ptui::scene::builtin;
use ptui::scene::description::{SceneDesc, SphereDesc};
use ptui::scene::load::parse;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// One sphere, ready to print.
#[derive(Clone, Debug)]
pub struct S {
    pub name: String,
    pub center: [f64; 3],
    pub radius: f64,
    pub material: Option<String>,
    pub color: Option<[f64; 3]>,
    pub emission: Option<[f64; 3]>,
    pub ior: Option<f64>,
}

impl S {
    fn from_desc(d: &SphereDesc) -> S {
        S {
            name: d
                .name
                .as_ref()
                .map(|n| n.get_ref().clone())
                .unwrap_or_default(),
            center: d.center.0,
            radius: d.radius.0,
            material: d.material.map(|m| format!("{m:?}").to_lowercase()),
            color: d
                .color
                .as_ref()
                .and_then(|c| c.get_ref().value())
                .map(|c| c.0),
            emission: d
                .emission
                .as_ref()
                .and_then(|e| e.get_ref().value())
                .map(|e| e.0),
            ior: d.ior.as_ref().map(|i| i.get_ref().0),
        }
    }
}

/// A scene to print: camera, spheres, and the `[check]` lines.
#[derive(Clone, Debug)]
pub struct Gen {
    pub position: [f64; 3],
    pub direction: [f64; 3],
    pub vfov: f64,
    pub near: f64,
    pub spheres: Vec<S>,
}

fn load(name: &str) -> Gen {
    let src = builtin::get(name).expect("built-in scene");
    let d: SceneDesc = parse(src, name).expect("built-in scenes parse");
    let c = &d.camera;
    Gen {
        position: c.position.expect("camera position").0,
        direction: c.direction.as_ref().expect("camera direction").get_ref().0,
        vfov: c.vfov.expect("vfov").0,
        near: c.near.map_or(0.0, |n| n.0),
        spheres: d.sphere.iter().map(S::from_desc).collect(),
    }
}

/// Shortest text that reads back as the same f64 (Rust's `{:?}` round-trips), valid TOML.
fn num(v: f64) -> String {
    format!("{v:?}")
}

fn v3(v: [f64; 3]) -> String {
    format!("[{}, {}, {}]", num(v[0]), num(v[1]), num(v[2]))
}

fn grey_or_v3(v: [f64; 3]) -> String {
    if v[0] == v[1] && v[1] == v[2] {
        num(v[0])
    } else {
        v3(v)
    }
}

impl Gen {
    fn to_toml(&self, header: &str, check: &str) -> String {
        let mut s = String::new();
        for line in header.lines() {
            let _ = writeln!(s, "# {line}");
        }
        s.push_str("# Written by `cargo xtask gen-extreme`; edit the generator, not this.\n\n");
        let _ = writeln!(s, "[camera]");
        let _ = writeln!(s, "position = {}", v3(self.position));
        let _ = writeln!(s, "direction = {}", v3(self.direction));
        let _ = writeln!(s, "vfov = {}", num(self.vfov));
        let _ = writeln!(s, "near = {}", num(self.near));
        let _ = writeln!(s, "\n[check]\n{}", check.trim());
        for sp in &self.spheres {
            let _ = writeln!(s, "\n[[sphere]]");
            let _ = writeln!(s, "name = \"{}\"", sp.name);
            if let Some(m) = &sp.material {
                let _ = writeln!(s, "material = \"{m}\"");
            }
            let _ = writeln!(s, "center = {}", v3(sp.center));
            let _ = writeln!(s, "radius = {}", num(sp.radius));
            if let Some(c) = sp.color {
                let _ = writeln!(s, "color = {}", grey_or_v3(c));
            }
            if let Some(e) = sp.emission {
                let _ = writeln!(s, "emission = {}", grey_or_v3(e));
            }
            if let Some(i) = sp.ior {
                let _ = writeln!(s, "ior = {}", num(i));
            }
        }
        s
    }

    /// Every object and the camera moved by `t`.
    fn translated(mut self, t: [f64; 3]) -> Gen {
        let add = |a: [f64; 3]| [a[0] + t[0], a[1] + t[1], a[2] + t[2]];
        self.position = add(self.position);
        for sp in &mut self.spheres {
            sp.center = add(sp.center);
        }
        self
    }

    /// All positions, radii and the near distance scaled by `k` (radiance is scale-free).
    fn scaled(mut self, k: f64) -> Gen {
        let mul = |a: [f64; 3]| a.map(|x| x * k);
        self.position = mul(self.position);
        self.near *= k;
        for sp in &mut self.spheres {
            sp.center = mul(sp.center);
            sp.radius *= k;
        }
        self
    }

    /// The radius-1e5 walls given radius `r`, centres moved along the wall's axis so the point
    /// of each wall nearest the room stays where it was.
    fn walls(mut self, r: f64) -> Gen {
        let room = [50.0, 40.8, 81.6];
        for sp in self.spheres.iter_mut().filter(|s| s.radius == 1e5) {
            let k = (0..3)
                .max_by(|&a, &b| {
                    (sp.center[a] - room[a])
                        .abs()
                        .total_cmp(&(sp.center[b] - room[b]).abs())
                })
                .unwrap_or(0);
            let u = (room[k] - sp.center[k]).signum();
            let plane = sp.center[k] + u * sp.radius;
            sp.center[k] = plane - u * r;
            sp.radius = r;
        }
        self
    }

    /// The light (the sphere named "light") with radius `r` and the same power: emission scales
    /// with 1 / r^2 (power = pi * area * radiance).
    fn light_radius(mut self, r: f64) -> Gen {
        for sp in self.spheres.iter_mut().filter(|s| s.name == "light") {
            let k = (sp.radius / r).powi(2);
            sp.emission = sp.emission.map(|e| e.map(|x| x * k));
            sp.radius = r;
        }
        self
    }

    fn with(mut self, s: S) -> Gen {
        self.spheres.push(s);
        self
    }
}

/// The invariance checks: 48x36 at 256 spp against an independent render of the reference.
const SAME_AS_CORNELL: &str = "width = 48\nheight = 36\nspp = 256\nsame_as = \"cornell\"";

/// (file stem, contents) of every generated scene.
pub fn generated() -> Vec<(String, String)> {
    let cornell = || load("cornell");
    let small = || load("cornell-small-light");
    let about = |a: &str| format!("about = \"{a}\"");
    let mut out = Vec::new();
    let mut push = |name: &str, g: Gen, header: &str, check: String| {
        out.push((name.to_string(), g.to_toml(header, &check)));
    };
    for (name, t) in [
        ("translate-1e4", [1e4, -1e4, 1e4]),
        ("translate-1e6", [1e6, 1e6, 1e6]),
    ] {
        let a = format!("cornell moved by ({:e}, {:e}, {:e})", t[0], t[1], t[2]);
        push(
            name,
            cornell().translated(t),
            &format!("`cornell` with every object and the camera moved by ({}, {}, {}): renders the same image.", t[0], t[1], t[2]),
            format!("{}\n{SAME_AS_CORNELL}", about(&a)),
        );
    }
    for (name, k) in [("scale-1e-3", 1e-3), ("scale-1e3", 1e3)] {
        push(
            name,
            cornell().scaled(k),
            &format!("`cornell` with all positions, radii and the near distance scaled by {k:e}\n(radiance unchanged): renders the same image."),
            format!("{}\n{SAME_AS_CORNELL}", about(&format!("cornell scaled by {k:e}"))),
        );
    }
    // The light sphere (radius 600) pokes 0.27 through the ceiling; the visible cap's radius rho
    // solves rho^2 (1/1200 + 1/(2R)) = 0.27 for a ceiling of radius R, so flatter walls show
    // (1/1200 + 1/2e5) / (1/1200) - 1 = 0.6% more of the light than R = 1e5 does: a real
    // difference, about 2 standard errors of the image mean at this size and spp. R = 1e8 is
    // therefore compared with R = 1e6 (0.06% apart), which isolates numerical trouble.
    push(
        "walls-1e6",
        cornell().walls(1e6),
        "`cornell` with wall spheres of radius 1e6 (centres moved so the planes stay put): renders\nthe same image as the radius-1e5 walls (up to the 0.6% more light the flatter ceiling\nuncovers, below this check's resolution).",
        format!("{}\n{SAME_AS_CORNELL}", about("cornell with walls of radius 1e6")),
    );
    push(
        "walls-1e8",
        cornell().walls(1e8),
        "`cornell` with wall spheres of radius 1e8 (centres moved so the planes stay put): renders\nthe same image as the radius-1e6 walls (which match radius 1e5).",
        format!(
            "{}\nwidth = 48\nheight = 36\nspp = 256\nsame_as = \"walls-1e6\"",
            about("cornell with walls of radius 1e8")
        ),
    );
    push(
        "index-matched",
        cornell().with(S {
            name: "invisible".into(),
            center: [50.0, 45.0, 100.0],
            radius: 14.0,
            material: Some("glass".into()),
            color: Some([1.0; 3]),
            emission: None,
            ior: Some(1.0),
        }),
        "`cornell` plus a glass sphere of index 1.0 and colour 1 in front of the balls: it refracts\nnothing and absorbs nothing, so the image equals `cornell` (only the noise differs: shadow\nrays through it are blocked, so light behind it is found by BSDF sampling alone; 8192 spp\nbecause with fewer those sparse hits leave the per-pixel variance estimates too skewed for\nthe z-tests once `cornell` itself samples its light's cap with little noise: at 1024 spp\nthree seeds out of three failed, at 16384 max|z| was 3.69 and mean |z| 0.72).",
        format!(
            "{}\nwidth = 48\nheight = 36\nspp = 8192\nsame_as = \"cornell\"",
            about("index-matched glass is invisible")
        ),
    );
    let small_check = "width = 48\nheight = 36\nspp = 256";
    push(
        "small-light-1e-2",
        small().light_radius(1e-2),
        "`cornell-small-light` with the light's radius 1e-2 and its emission scaled by (1.5 / 1e-2)^2,\nso the power is unchanged: close to the point-light limit, finite, no invalid samples.",
        format!("{}\n{small_check}", about("light of radius 1e-2, emission 9e6")),
    );
    push(
        "small-light-1e-4",
        small().light_radius(1e-4),
        "`cornell-small-light` with the light's radius 1e-4 and the same power (emission 9e10):\nthe same image as radius 1e-2 (both are the point-light limit to within noise).",
        format!(
            "{}\n{small_check}\nsame_as = \"small-light-1e-2\"",
            about("light of radius 1e-4, emission 9e10")
        ),
    );
    out
}

/// Variants past the committed ones, used to find where invariance breaks (not committed).
fn probes() -> Vec<(String, String)> {
    let mut out = Vec::new();
    let check = |a: String| format!("about = \"{a}\"\n{SAME_AS_CORNELL}");
    for t in [1e8, 1e10, 1e12, 1e13, 1e14, 1e15] {
        out.push((
            format!("translate-{t:e}"),
            load("cornell")
                .translated([t; 3])
                .to_toml("probe", &check(format!("translate {t:e}"))),
        ));
    }
    for k in [
        1e-6, 1e6, 1e-9, 1e9, 1e-12, 1e12, 1e-15, 1e15, 1e-20, 1e20, 1e-25, 1e24,
    ] {
        out.push((
            format!("scale-{k:e}"),
            load("cornell")
                .scaled(k)
                .to_toml("probe", &check(format!("scale {k:e}"))),
        ));
    }
    for r in [1e10, 1e12, 1e14] {
        out.push((
            format!("walls-{r:e}"),
            load("cornell")
                .walls(r)
                .to_toml("probe", &check(format!("walls {r:e}"))),
        ));
    }
    for r in [1e-6, 1e-8, 1e-10, 1e-12, 1e-13] {
        out.push((
            format!("small-light-{r:e}"),
            load("cornell-small-light").light_radius(r).to_toml(
                "probe",
                &format!(
                    "about = \"light {r:e}\"\nwidth = 48\nheight = 36\nspp = 256\nsame_as = \"small-light-1e-2\""
                ),
            ),
        ));
    }
    out
}

/// Write the generated scenes into `extreme` (scenes/extreme/), or with `probe` the
/// beyond-the-limit variants into that directory instead.
pub fn write(probe: Option<PathBuf>, extreme: &Path) -> std::io::Result<()> {
    let (files, dir) = match probe {
        Some(dir) => (probes(), dir),
        None => (generated(), extreme.to_path_buf()),
    };
    std::fs::create_dir_all(&dir)?;
    for (name, text) in files {
        let path = dir.join(format!("{name}.toml"));
        std::fs::write(&path, text)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
