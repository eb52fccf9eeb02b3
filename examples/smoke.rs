use rangesynth::{gpu::ContextOptions, Renderer, Scene};
fn main() {
    let r = Renderer::new(&ContextOptions { validation: true, device: None }).unwrap();
    println!("device {}", r.context().device_name());
    let toml = r#"
[sensor]
kind = "orthographic"
width = 40
height = 12
pitch = [0.1, 0.2]
origin = [-2.45, 1.1]
theta_deg = 45.0
[shadow]
mode = "depth"
[[object]]
model = "builtin:step"
"#;
    let scene = Scene::from_toml(toml, std::path::Path::new(".")).unwrap();
    let out = r.render(&scene).unwrap();
    for row in 0..12 {
        let s: String = (0..40).map(|c| { let i = row*40+c; let l = out.label[i]; if l==0 && out.label_unshadowed[i]!=0 {'#'} else {std::char::from_digit(l,36).unwrap()} }).collect();
        println!("{s}  z={:?}", &out.z[row*40..row*40+3]);
    }
    println!("{:?}", out.timings);
    println!("msgs: {:?}", r.context().take_validation_messages());
}
