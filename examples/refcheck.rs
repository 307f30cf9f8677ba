use ptui::{reference, render::Renderer, scene, settings::*};
use std::sync::{atomic::AtomicBool, Arc};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let spp: u32 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(64);
    let integ = if args.get(2).map(|s| s.as_str()) == Some("naive") {
        IntegratorKind::Naive
    } else {
        IntegratorKind::Path
    };
    let r = reference::load(std::path::Path::new("../shared/refs/cornell.exr")).unwrap();
    let sc = Arc::new(scene::load("cornell").unwrap());
    let mut s = RenderSettings::merged(&[&sc.render]);
    s.integrator = integ;
    s.spp = spp;
    let mut ren = Renderer::new(sc, s).unwrap();
    let cancel = AtomicBool::new(false);
    let mut next = 1;
    ren.render(&cancel, |ren| {
        let n = ren.stats().complete_passes;
        if n == next {
            next *= 2;
            let img = ren.film().mean_rgb_f32();
            let m = reference::channel_means(&img);
            let e = ren.film().error_estimate();
            println!(
                "{n:5} spp t={:6.2}s rmse {:.5} est {:.5} means {:.5} {:.5} {:.5}",
                ren.stats().elapsed.as_secs_f64(),
                reference::rmse(&img, &r.data),
                e.rmse,
                m[0],
                m[1],
                m[2]
            );
        }
        true
    });
    println!("ref means {:?}", r.channel_means());
}
