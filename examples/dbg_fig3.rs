use dsc_seg::dim::D2;
use dsc_seg::phantom::{self, Phantom2Kind};
use dsc_seg::segment::{ImageView, Init, InitDisk, SegmentParams, Segmentation};
fn main() {
    let n = 128;
    let ph = Phantom2Kind::Fig3.generate(n, 0.1, 4);
    let seed = phantom::fig3_seed(n);
    let mut p = SegmentParams::new(2);
    p.label_flips = false;
    p.step_fraction = 0.25;
    p.max_iterations = 800;
    p.init = Init::Disks(vec![InitDisk {
        x: seed.x,
        y: seed.y,
        r: seed.r,
        phase: 1,
    }]);
    let img = ImageView::new_2d(n, n, &ph.image).unwrap();
    let mut s = Segmentation::<D2>::new(img, p).unwrap();
    let r = s.run(|_| {});
    println!(
        "components {} {} iters {}",
        s.complex().components(0),
        s.complex().components(1),
        r.iterations
    );
    let c = s.complex();
    let dp = s.dsc_params();
    for t in c.cell_ids() {
        let q = c.cell_points(t);
        let g = (q[0] + q[1] + q[2]) / 3.0;
        if c.label(t) == 0 && g.x > 45.5 && g.x < 83.5 && g.y < 33.0 && g.y > 14.0 {
            let kinds: Vec<_> = c
                .cell(t)
                .iter()
                .map(|&v| format!("{:?}", c.class(v).kind))
                .collect();
            let nbl: Vec<_> = c
                .neighbours(t)
                .iter()
                .map(|n| n.map(|n| c.label(n)))
                .collect();
            println!(
                "{:?} L{} nb {:?} q {:.4} area {:.4} deg {} {:?} {:?}",
                t,
                c.label(t),
                nbl,
                c.quality(t),
                c.measure(t),
                c.is_degenerate(t, dp),
                g,
                kinds
            );
        }
    }
}
