//! Writes every 2D phantom as binary PGM files (image, and ground truth with
//! phase `k` as gray `k·255/(N−1)`) for checks by other programs, e.g. a
//! NumPy transcription of the geometry:
//!
//! `cargo run --release --example phantom_dump -- OUT_DIR [SIZE...] [--sigma S] [--seed N] [--3d N]`
//!
//! With `--3d N` the 3D phantoms are also written as raw `N³` u8 volumes
//! (x fastest): `NAME_N.u8` (image) and `NAME_N_gt.u8` (phase index).
use dsc_seg::phantom::{Phantom2, Phantom2Kind, Phantom3Kind};
use std::io::Write;

fn write_pgm(path: &std::path::Path, w: usize, h: usize, data: &[u8]) -> std::io::Result<()> {
    let mut f = std::io::BufWriter::new(std::fs::File::create(path)?);
    write!(f, "P5\n{w} {h}\n255\n")?;
    f.write_all(data)
}

fn main() -> std::io::Result<()> {
    let mut args = std::env::args().skip(1);
    let out = std::path::PathBuf::from(args.next().expect("usage: phantom_dump OUT_DIR [SIZE...]"));
    let (mut sizes, mut sigma, mut seed, mut n3) = (Vec::new(), 0.0, 0u64, None);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--sigma" => sigma = args.next().and_then(|s| s.parse().ok()).expect("--sigma S"),
            "--seed" => seed = args.next().and_then(|s| s.parse().ok()).expect("--seed N"),
            "--3d" => n3 = args.next().and_then(|s| s.parse::<usize>().ok()),
            s => sizes.push(s.parse::<usize>().expect("size")),
        }
    }
    if sizes.is_empty() {
        sizes.push(256);
    }
    std::fs::create_dir_all(&out)?;
    for kind in Phantom2Kind::ALL {
        for &n in &sizes {
            let p: Phantom2 = kind.generate(n, sigma, seed);
            let stem = format!("{}_{n}", kind.name());
            write_pgm(&out.join(format!("{stem}.pgm")), n, n, &p.image_u8())?;
            write_pgm(&out.join(format!("{stem}_gt.pgm")), n, n, &p.truth_gray())?;
        }
    }
    if let Some(n) = n3 {
        for kind in Phantom3Kind::ALL {
            let p = kind.generate(n, sigma, seed);
            let img: Vec<u8> = p.image.iter().map(|&v| (v * 255.0).round() as u8).collect();
            std::fs::write(out.join(format!("{}_{n}.u8", kind.name())), img)?;
            std::fs::write(out.join(format!("{}_{n}_gt.u8", kind.name())), &p.truth)?;
        }
    }
    println!(
        "wrote {} phantoms to {}",
        Phantom2Kind::ALL.len() * sizes.len(),
        out.display()
    );
    Ok(())
}
