mod ring_support;
use ring_support::*;
use whycode::detect::ring::RingReader;
use whycode::family::{Decoder, Family};

fn run(label: &str, bits: u32, dist: u32, diameter: f64, f: impl Fn(&mut View, u32)) {
    let fam = Family::generate(bits, dist).unwrap();
    let reader = RingReader::new(Some(Decoder::new(&fam))).with_min_pixels_per_sector(1.0);
    let mut errs = vec![];
    let mut wrong = 0;
    let mut unknown = 0;
    let mut conf_ok = 0.0;
    let mut conf_wrong: f64 = 0.0;
    let n = 40u32;
    for k in 0..n {
        let id = 1 + (k * 7) % fam.len() as u32;
        let code = fam.code(id).unwrap();
        let rot = k as f64 * 0.377;
        let mut view = View::new(bits, code, diameter, rot);
        view.offset = ((k as f64 * 0.13) % 1.0, (k as f64 * 0.29) % 1.0);
        view.seed = k as u64;
        f(&mut view, k);
        let r = render(&view);
        let rd = reader.read(&r.image, &r.ellipse, BLACK, WHITE);
        if rd.id == 0 {
            unknown += 1;
        } else if rd.id != id {
            wrong += 1;
            conf_wrong = conf_wrong.max(rd.confidence);
            println!(
                "   WRONG es {:.3} weak {:.2} pps {:.2} er {} conf {:.2}",
                rd.edge_strength, rd.weakest_bit, rd.pixels_per_sector, rd.erasures, rd.confidence
            );
        } else {
            errs.push(angle_error(rd.yaw.unwrap(), r.yaw).to_degrees());
            conf_ok += rd.confidence;
            if label == "motion" && k < 3 {
                println!(
                    "   ok es {:.3} weak {:.2} pps {:.2} er {} conf {:.2}",
                    rd.edge_strength,
                    rd.weakest_bit,
                    rd.pixels_per_sector,
                    rd.erasures,
                    rd.confidence
                );
            }
        }
    }
    let mean = errs.iter().sum::<f64>() / errs.len().max(1) as f64;
    let max = errs.iter().cloned().fold(0.0, f64::max);
    println!("{label:>10} bits {bits} d{dist} diam {diameter}: ok {} wrong {wrong} (maxconf {conf_wrong:.2}) unknown {unknown} yaw mean {mean:.3} max {max:.3} conf_ok {:.2}", errs.len(), conf_ok / errs.len().max(1) as f64);
}

#[test]
fn scratch() {
    for bits in [8u32, 12, 16] {
        for diameter in [12.0, 16.0, 30.0, 50.0, 100.0] {
            for dist in [1, 2] {
                run("noise", bits, dist, diameter, |v, _| {
                    v.noise = 8.0;
                    v.gaussian_blur = 0.7;
                });
                run("blur", bits, dist, diameter, |v, _| {
                    v.gaussian_blur = diameter / 40.0;
                });
                run("tilt", bits, dist, diameter, |v, k| {
                    v.tilt = 1.05;
                    v.tilt_direction = k as f64;
                    v.gaussian_blur = 0.5;
                });
                run("motion", bits, dist, diameter, |v, k| {
                    v.motion_blur = diameter / 8.0;
                    v.motion_direction = k as f64;
                    v.noise = 3.0;
                });
            }
        }
    }
}
