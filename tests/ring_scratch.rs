mod ring_support;
use ring_support::*;
use whycode::detect::ring::RingReader;
use whycode::family::{Decoder, Family};

#[test]
fn scratch() {
    for bits in [4u32, 8, 12, 16] {
        let fam = Family::generate(bits, 2).unwrap();
        let reader = RingReader::new(Some(Decoder::new(&fam)));
        for diameter in [12.0, 16.0, 24.0, 40.0, 100.0] {
            let mut errs = vec![];
            let mut wrong = 0;
            let mut unknown = 0;
            let mut confs = vec![];
            for k in 0..20u32 {
                let id = 1 + (k * 7) % fam.len() as u32;
                let code = fam.code(id).unwrap();
                let rot = k as f64 * 0.377;
                let mut view = View::new(bits, code, diameter, rot);
                view.offset = ((k as f64 * 0.13) % 1.0, (k as f64 * 0.29) % 1.0);
                view.gaussian_blur = 0.5;
                let r = render(&view);
                let rd = reader.read(&r.image, &r.ellipse, BLACK, WHITE);
                if rd.id == 0 {
                    unknown += 1;
                } else if rd.id != id {
                    wrong += 1;
                } else {
                    errs.push(angle_error(rd.yaw.unwrap(), r.yaw).to_degrees());
                }
                confs.push(rd.confidence);
            }
            let mean = errs.iter().sum::<f64>() / errs.len().max(1) as f64;
            let max = errs.iter().cloned().fold(0.0, f64::max);
            println!("bits {bits} d {diameter}: ok {} wrong {wrong} unknown {unknown} yaw mean {mean:.3} max {max:.3} conf {:?}", errs.len(), confs.iter().map(|c| (c*100.0).round()/100.0).collect::<Vec<_>>());
        }
    }
}
