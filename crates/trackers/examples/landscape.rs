use contour_obs::{Affine2, GreyView, OdobezLikelihood, OdobezSettings, Template, WuLikelihood, WuSettings};
use scene_synth::{Scenario, ScenarioParams, Scene};
fn main() {
    let sc = match std::env::args().nth(1).as_deref() { Some("mclutter") => Scenario::Mclutter, Some("distractor") => Scenario::Distractor, _ => Scenario::Occlusion };
    let frame: usize = std::env::args().nth(2).map(|s| s.parse().unwrap()).unwrap_or(0);
    let p = ScenarioParams::preset(sc);
    let scene = Scene::new(&p, 1).unwrap();
    let (img, t) = scene.render_frame(frame).unwrap();
    let data = scene_synth::to_f32(&img);
    let view = GreyView::new(img.width() as usize, img.height() as usize, &data).unwrap();
    let lik = OdobezLikelihood::new(OdobezSettings::default(), &Template::UnitCircle).unwrap();
    let wu = WuLikelihood::new(WuSettings::default(), &Template::UnitCircle).unwrap();
    let mut ws = lik.workspace().unwrap();
    let e = t.ellipse;
    println!("truth {:?} density {} class {}", e, t.edge_density, t.clutter_class);
    for ds in [0.8, 0.9, 1.0, 1.1, 1.2, 1.4] {
        let mut row = String::new();
        for dx in [-8.0, -4.0, -2.0, 0.0, 2.0, 4.0, 8.0] {
            let pose = Affine2::from_ellipse(e.cx + dx, e.cy, e.a * ds, e.b * ds, e.angle);
            let v = lik.log_likelihood(&mut ws, &view, &pose).unwrap();
            let w = wu.log_likelihood(&mut ws, &view, &pose, 0.08).unwrap();
            row += &format!("{v:7.2}/{w:7.2} ");
        }
        println!("scale {ds}: {row}");
    }
}
