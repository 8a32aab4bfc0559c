//! Physical space: an anisotropic, flipped and offset NIfTI volume is
//! segmented as the physical object it holds, and the outputs keep its
//! geometry.

use dsc_seg::io::frame::Affine;
use dsc_seg::io::{save_nifti, FrameSource, Volume};
use dsc_seg::pipeline::{run_segment3d, Segment3dJob, Source};
use dsc_seg::segment::SegmentParams;
use dsc_seg::segmented::Outputs;
use vtkio::model::{DataSet, Piece, Vtk};

/// Voxels of 0.5 × 0.5 × 2 mm, x flipped, origin offset.
const AFFINE: Affine = [
    [-0.5, 0.0, 0.0, 30.0],
    [0.0, 0.5, 0.0, -12.0],
    [0.0, 0.0, 2.0, 5.0],
];
const DIMS: [usize; 3] = [48, 48, 12];
/// The ball: centre in world millimetres and radius.
const CENTRE: [f64; 3] = [18.25, -0.25, 15.0];
const RADIUS: f64 = 7.0;

fn world(i: usize, j: usize, k: usize) -> [f64; 3] {
    AFFINE.map(|r| r[0] * i as f64 + r[1] * j as f64 + r[2] * k as f64 + r[3])
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|c| (a[c] - b[c]).powi(2)).sum::<f64>().sqrt()
}

/// The points of a `.vtu` or `.vtp` file and the corners of its cells
/// (tetrahedra or triangles), as a viewer reads them.
fn points_and_cells(path: &std::path::Path) -> (Vec<[f64; 3]>, Vec<Vec<usize>>) {
    let vtk = Vtk::import(path).unwrap();
    let (points, cells) = match vtk.data {
        DataSet::PolyData { pieces, .. } => {
            let Piece::Inline(piece) = pieces.into_iter().next().unwrap() else {
                panic!("not inline")
            };
            (piece.points, piece.polys.expect("triangles"))
        }
        DataSet::UnstructuredGrid { pieces, .. } => {
            let Piece::Inline(piece) = pieces.into_iter().next().unwrap() else {
                panic!("not inline")
            };
            (piece.points, piece.cells.cell_verts)
        }
        _ => panic!("neither polydata nor an unstructured grid"),
    };
    let flat: Vec<f64> = points.cast_into().unwrap();
    let points = flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    let (connectivity, offsets) = cells.into_xml();
    let mut start = 0;
    let cells = offsets
        .iter()
        .map(|&end| {
            let cell = connectivity[start..end as usize]
                .iter()
                .map(|&v| v as usize)
                .collect();
            start = end as usize;
            cell
        })
        .collect();
    (points, cells)
}

/// The interface points of `interface.vtp`.
fn interface_points(path: &std::path::Path) -> Vec<[f64; 3]> {
    points_and_cells(path).0
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|c| a[c] - b[c])
}

fn triple(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
        + a[2] * (b[0] * c[1] - b[1] * c[0])
}

#[test]
fn an_anisotropic_flipped_nifti_ball_is_round_in_millimetres_and_keeps_its_geometry() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("ball.nii.gz");
    let volume = Volume::from_fn(DIMS[0], DIMS[1], DIMS[2], |i, j, k| {
        if distance(world(i, j, k), CENTRE) < RADIUS {
            0.8
        } else {
            0.2
        }
    })
    .with_spacing([0.5, 0.5, 2.0])
    .with_affine(AFFINE, FrameSource::NiftiSform);
    save_nifti(&input, &volume).unwrap();

    let mut params = SegmentParams::new_3d(2);
    params.max_iterations = 60;
    let job = Segment3dJob {
        source: Source::File(input.clone()),
        out: dir.path().join("out"),
        params,
        init_labels: None,
        init_surface: None,
        outputs: Outputs::ALL,
        quiet: true,
        channel: None,
        time_point: None,
        spacing: None,
    };
    run_segment3d(&job).unwrap();

    // labels.nii.gz: the input's shape and affine, the ball's volume.
    let labels = Volume::load(job.out.join("labels.nii.gz")).unwrap();
    let input_frame = Volume::load(&input).unwrap().frame();
    assert_eq!(labels.dims(), DIMS);
    assert_eq!(labels.frame().index_to_world, input_frame.index_to_world);
    assert_eq!(labels.frame().source, FrameSource::NiftiSform);
    // uint8 labels load as value / 255: phase 1 is any non-zero voxel.
    let inside = labels.data().iter().filter(|&&v| v > 0.0).count() as f64 * 0.5;
    let ball = 4.0 / 3.0 * std::f64::consts::PI * RADIUS.powi(3);
    assert!((inside / ball - 1.0).abs() < 0.05, "{inside} mm³ vs {ball}");

    // interface.vtp: centred on the ball's world position, round in mm.
    let points = interface_points(&job.out.join("interface.vtp"));
    assert!(points.len() > 50);
    let n = points.len() as f64;
    let centroid: [f64; 3] = std::array::from_fn(|c| points.iter().map(|p| p[c]).sum::<f64>() / n);
    let off = distance(centroid, CENTRE);
    let radii: Vec<f64> = points.iter().map(|&p| distance(p, centroid)).collect();
    let mean = radii.iter().sum::<f64>() / n;
    let sd = (radii.iter().map(|r| (r - mean).powi(2)).sum::<f64>() / n).sqrt();
    // Spread: the radii's standard deviation over their mean.
    let spread = sd / mean;
    // Extents along the world axes: a ball treated as isotropic voxels
    // would come out 4 times flatter along z than along x.
    let extent = |c: usize| {
        let (lo, hi) = points
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p[c]), hi.max(p[c]))
            });
        hi - lo
    };
    let (ex, ey, ez) = (extent(0), extent(1), extent(2));
    eprintln!(
        "centre off by {off:.3} mm, radius {mean:.3} mm, spread {:.1}%, extents {ex:.2} {ey:.2} {ez:.2} mm",
        100.0 * spread
    );
    assert!(off < 1.0, "centre off by {off} mm");
    assert!((mean - RADIUS).abs() < 0.1 * RADIUS, "mean radius {mean}");
    // Within one z voxel (2 mm), the size the data resolves.
    assert!((ez - ex).abs() < 2.0 && (ey - ex).abs() < 2.0, "extents");
    assert!(spread <= 0.10, "radius spread {spread}");

    // The affine mirrors (x flipped): the cells must still be positively
    // oriented in the world, and the interface normals point from phase 0
    // (outside) into phase 1 (the ball), so the triangles enclose minus
    // the ball's volume.
    let (points, tets) = points_and_cells(&job.out.join("mesh.vtu"));
    let inverted = tets
        .iter()
        .filter(|t| {
            let [a, b, c, d] = [0, 1, 2, 3].map(|k| points[t[k]]);
            triple(sub(b, a), sub(c, a), sub(d, a)) <= 0.0
        })
        .count();
    assert_eq!(
        inverted,
        0,
        "{inverted} of {} tetrahedra inverted",
        tets.len()
    );
    let (points, triangles) = points_and_cells(&job.out.join("interface.vtp"));
    let enclosed: f64 = triangles
        .iter()
        .map(|t| triple(points[t[0]], points[t[1]], points[t[2]]) / 6.0)
        .sum();
    assert!(
        (enclosed + inside).abs() < 0.05 * inside,
        "enclosed {enclosed} mm³, ball {inside}"
    );
}

/// The same volume with its voxel size given in different units (a
/// micro-CT in millimetres or micrometres): the mesh is sized in voxels, so
/// every run builds about the same mesh and gives the same labels, where
/// sizes fixed in absolute units once refused the small unit and built
/// billions of cells for the large one.
#[test]
fn the_mesh_and_labels_do_not_depend_on_the_unit_of_the_voxel_size() {
    use dsc_seg::dim::D3;
    use dsc_seg::segment::{ImageView, Segmentation};
    let dims = [28, 24, 20];
    let centre = [13.0, 11.5, 9.5];
    let data: Vec<f32> = (0..dims[2])
        .flat_map(|k| (0..dims[1]).flat_map(move |j| (0..dims[0]).map(move |i| [i, j, k])))
        .map(|[i, j, k]| {
            let p = [i as f64, j as f64, k as f64];
            if distance(p, centre) < 7.0 {
                0.8
            } else {
                0.2
            }
        })
        .collect();
    let run = |unit: f64| {
        let view = ImageView::new_3d(dims, &data)
            .unwrap()
            .with_spacing([unit, 1.5 * unit, unit])
            .unwrap();
        // To convergence: the two-phase default ends with a fine finish,
        // which refines the interfaces, so runs cut by an iteration cap
        // before and after it are not at the same stage.
        let mut seg = Segmentation::<D3>::new(view, SegmentParams::new_3d(2)).unwrap();
        assert!(seg.run(|_| {}).converged, "voxel unit {unit}");
        (seg.complex().cell_count(), seg.label_image())
    };
    let (cells, labels) = run(1.0);
    for unit in [1e-3, 1e3] {
        let (c, l) = run(unit);
        let agree = l.iter().zip(&labels).filter(|(a, b)| a == b).count() as f64;
        let agree = agree / labels.len() as f64;
        assert!(
            (c as f64 / cells as f64 - 1.0).abs() < 0.05,
            "voxel unit {unit}: {c} cells against {cells}"
        );
        assert!(agree > 0.99, "voxel unit {unit}: labels agree on {agree}");
    }
}

/// The values of an `image.vti` written by dsc-seg (one Float32 array,
/// base64 with a UInt64 length header).
fn vti_values(path: &std::path::Path) -> Vec<f32> {
    use base64::{engine::general_purpose::STANDARD, Engine};
    let text = std::fs::read_to_string(path).unwrap();
    let start = text.find("format=\"binary\">").unwrap() + "format=\"binary\">".len();
    let encoded = text[start..].split("</DataArray>").next().unwrap().trim();
    // The length header is 8 bytes: 12 base64 characters with its padding.
    let (header, data) = encoded.split_at(12);
    let len = u64::from_le_bytes(STANDARD.decode(header).unwrap().try_into().unwrap());
    let bytes = STANDARD.decode(data).unwrap();
    assert_eq!(bytes.len() as u64, len);
    bytes
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect()
}

fn value_range(v: &[f32]) -> (f32, f32) {
    v.iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &x| {
            (lo.min(x), hi.max(x))
        })
}

/// `image.vti` holds what the file holds (Hounsfield units of a CT, the
/// counts of a 16-bit image), so that a viewer's probe and colour bar read
/// the same numbers as `report.json` and the input.
#[test]
fn image_vti_holds_the_input_values_in_its_units() {
    let dir = tempfile::tempdir().unwrap();
    // A CT-like volume in HU: air at -1000 around a ball of soft tissue at 40.
    let ct = Volume::from_fn(16, 16, 16, |i, j, k| {
        let d = distance([i as f64, j as f64, k as f64], [7.5; 3]);
        if d < 5.0 {
            40.0
        } else {
            -1000.0
        }
    });
    let ct_path = dir.path().join("ct.nii.gz");
    save_nifti(&ct_path, &ct).unwrap();
    // A 16-bit image using a small part of its range.
    let png_path = dir.path().join("counts.png");
    image::ImageBuffer::<image::Luma<u16>, _>::from_fn(32, 32, |x, y| {
        let inside = (x as f64 - 16.0).powi(2) + (y as f64 - 16.0).powi(2) < 64.0;
        image::Luma([if inside { 3000u16 } else { 1000 }])
    })
    .save(&png_path)
    .unwrap();
    for (sub, input, expected) in [
        ("segment3d", &ct_path, (-1000.0, 40.0)),
        ("segment", &png_path, (1000.0, 3000.0)),
    ] {
        let out = dir.path().join(sub);
        let o = crate::cli::bin()
            .arg(sub)
            .arg(input)
            .args(["--quiet", "--outputs", "image", "--out"])
            .arg(&out)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let (lo, hi) = value_range(&vti_values(&out.join("image.vti")));
        assert!(
            (lo - expected.0).abs() < 0.01 && (hi - expected.1).abs() < 0.01,
            "{sub}: image.vti spans {lo}..{hi}, the input {expected:?}"
        );
    }
}

/// The length weight is a width in voxel steps whatever the voxel size: a
/// noisy ball in voxels of 4 mm (a resampled clinical volume) and of
/// 0.25 mm has the energy and the labels of the same voxels at 1 mm. The
/// data term counts voxels while the interface is measured in the volume's
/// unit, so a weight taken per unit area once made the boundary 16 times
/// dearer at 4 mm (a skull-stripped MRI resampled to 4 mm lost its brain to
/// the background in a label-flip round).
#[test]
fn the_length_weight_does_not_depend_on_the_size_of_the_voxels() {
    use dsc_seg::dim::D3;
    use dsc_seg::phantom::noise::add_gaussian_noise;
    use dsc_seg::segment::{ImageView, Segmentation};
    let dims = [24, 24, 24];
    let mut data: Vec<f32> = (0..dims[2])
        .flat_map(|k| (0..dims[1]).flat_map(move |j| (0..dims[0]).map(move |i| [i, j, k])))
        .map(|[i, j, k]| {
            let p = [i as f64, j as f64, k as f64];
            if distance(p, [11.5; 3]) < 6.5 {
                0.8
            } else {
                0.2
            }
        })
        .collect();
    add_gaussian_noise(&mut data, 0.2, 1);
    let run = |voxel: f64| {
        let view = ImageView::new_3d(dims, &data)
            .unwrap()
            .with_spacing([voxel; 3])
            .unwrap();
        let mut seg = Segmentation::<D3>::new(view, SegmentParams::new_3d(2)).unwrap();
        let first = seg.step();
        seg.run(|_| {});
        (first.energy, first.data_energy, seg.label_image())
    };
    let (energy, data_energy, labels) = run(1.0);
    let ball = labels.iter().filter(|&&l| l != labels[0]).count();
    assert!(ball > 800, "the ball at 1 mm holds {ball} voxels");
    for voxel in [4.0, 0.25] {
        let (e, d, l) = run(voxel);
        assert!(
            (d / data_energy - 1.0).abs() < 1e-6 && (e / energy - 1.0).abs() < 1e-6,
            "{voxel} mm voxels: energy {e} (data {d}) against {energy} (data {data_energy})"
        );
        let agree = l.iter().zip(&labels).filter(|(a, b)| a == b).count() as f64;
        let agree = agree / labels.len() as f64;
        assert!(agree > 0.99, "{voxel} mm voxels: labels agree on {agree}");
    }
}
