//! End-to-end tests of the safe TetGen wrapper.

use tetgen_sys::{signed_volume, tetrahedralize, Plc, Region, Switches, TetMesh, TetgenError};

/// Surface of the axis-aligned cube `[lo, hi]^3` (8 points, 12 triangles),
/// with point indices offset by `offset`.
fn cube(lo: f64, hi: f64, offset: u32) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let points = (0..8)
        .map(|i| {
            let c = |bit: u32| if i & (1 << bit) != 0 { hi } else { lo };
            [c(0), c(1), c(2)]
        })
        .collect();
    // Corner index = x + 2y + 4z; two triangles per face.
    let quads = [
        [0, 2, 3, 1], // z = lo
        [4, 5, 7, 6], // z = hi
        [0, 1, 5, 4], // y = lo
        [2, 6, 7, 3], // y = hi
        [0, 4, 6, 2], // x = lo
        [1, 3, 7, 5], // x = hi
    ];
    let triangles = quads
        .iter()
        .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
        .map(|t: [u32; 3]| t.map(|i| i + offset))
        .collect();
    (points, triangles)
}

fn unit_cube() -> Plc {
    let (points, triangles) = cube(0.0, 1.0, 0);
    Plc {
        points,
        triangles,
        regions: Vec::new(),
    }
}

fn assert_positive(mesh: &TetMesh) {
    for t in 0..mesh.tets.len() {
        let [a, b, c, d] = mesh.tets[t].map(|i| mesh.points[i as usize]);
        assert!(
            signed_volume(a, b, c, d) > 0.0,
            "tet {t} not positively oriented"
        );
        // Exact check too: Shewchuk's orient3d is negative for right-handed tets.
        let c3 = |p: [f64; 3]| robust::Coord3D {
            x: p[0],
            y: p[1],
            z: p[2],
        };
        assert!(robust::orient3d(c3(a), c3(b), c3(c), c3(d)) < 0.0);
    }
}

fn total_volume(mesh: &TetMesh) -> f64 {
    (0..mesh.tets.len()).map(|t| mesh.tet_volume(t)).sum()
}

#[test]
fn unit_cube_quality_mesh() {
    let switches = Switches {
        quality: Some(1.5),
        max_volume: Some(0.01),
        ..Switches::default()
    };
    let mesh = tetrahedralize(&unit_cube(), &switches).expect("tetrahedralize");
    assert!(mesh.tets.len() > 100, "only {} tets", mesh.tets.len());
    assert!(mesh.tet_attributes.is_empty());
    // Input points come first, unchanged.
    assert_eq!(&mesh.points[..8], &unit_cube().points[..]);
    assert_positive(&mesh);
    let volume = total_volume(&mesh);
    assert!((volume - 1.0).abs() < 1e-9, "volume {volume}");
    for t in 0..mesh.tets.len() {
        assert!(mesh.tet_volume(t) <= 0.01 * (1.0 + 1e-9));
    }
}

#[test]
fn unit_cube_plain_and_min_angle() {
    let mesh = tetrahedralize(&unit_cube(), &Switches::default()).unwrap();
    assert_eq!(mesh.points.len(), 8);
    assert_positive(&mesh);
    assert!((total_volume(&mesh) - 1.0).abs() < 1e-12);

    let switches = Switches {
        quality: Some(2.0),
        min_dihedral_angle: Some(10.0),
        preserve_surface: true,
        ..Switches::default()
    };
    let mesh = tetrahedralize(&unit_cube(), &switches).unwrap();
    assert_positive(&mesh);
    assert!((total_volume(&mesh) - 1.0).abs() < 1e-9);
}

#[test]
fn nested_cubes_with_two_regions() {
    let (mut points, mut triangles) = cube(0.0, 3.0, 0);
    let (inner_points, inner_triangles) = cube(1.0, 2.0, 8);
    points.extend(inner_points);
    triangles.extend(inner_triangles);
    let plc = Plc {
        points,
        triangles,
        regions: vec![
            Region {
                seed: [0.5, 0.5, 0.5],
                attribute: 7,
                max_volume: None,
            },
            Region {
                seed: [1.5, 1.5, 1.5],
                attribute: -3,
                max_volume: Some(0.005),
            },
        ],
    };
    let switches = Switches {
        quality: Some(1.5),
        region_attributes: true,
        ..Switches::default()
    };
    let mesh = tetrahedralize(&plc, &switches).unwrap();
    assert_positive(&mesh);
    assert_eq!(mesh.tet_attributes.len(), mesh.tets.len());
    let (mut outer, mut inner) = (0.0, 0.0);
    for (t, &a) in mesh.tet_attributes.iter().enumerate() {
        match a {
            7 => outer += mesh.tet_volume(t),
            -3 => {
                inner += mesh.tet_volume(t);
                assert!(mesh.tet_volume(t) <= 0.005 * (1.0 + 1e-9));
            }
            other => panic!("unexpected attribute {other}"),
        }
    }
    assert!((outer - 26.0).abs() < 1e-9, "outer volume {outer}");
    assert!((inner - 1.0).abs() < 1e-9, "inner volume {inner}");
}

#[test]
fn open_surface_is_rejected() {
    let mut plc = unit_cube();
    plc.triangles.pop();
    let err = tetrahedralize(&plc, &Switches::default()).unwrap_err();
    assert!(
        matches!(err, TetgenError::NonManifoldEdge { count: 1, .. }),
        "{err}"
    );
}

#[test]
fn nan_is_rejected() {
    let mut plc = unit_cube();
    plc.points[3][1] = f64::NAN;
    let err = tetrahedralize(&plc, &Switches::default()).unwrap_err();
    assert_eq!(err, TetgenError::InvalidCoordinate { point: 3 });
    plc.points[3][1] = f64::INFINITY;
    assert!(tetrahedralize(&plc, &Switches::default()).is_err());
}

#[test]
fn self_intersecting_surfaces_are_rejected() {
    // Two overlapping cubes: each is closed, together they intersect.
    // Debian's TetGen 1.5.0 segfaults on this input if it is not caught.
    let (mut points, mut triangles) = cube(0.0, 2.0, 0);
    let (p2, t2) = cube(1.0, 3.0, 8);
    points.extend(p2);
    triangles.extend(t2);
    let plc = Plc {
        points,
        triangles,
        regions: Vec::new(),
    };
    let err = tetrahedralize(&plc, &Switches::default()).unwrap_err();
    assert!(matches!(err, TetgenError::SelfIntersection { .. }), "{err}");

    // A cube with its top corner pushed down through the bottom face.
    let mut plc = unit_cube();
    plc.points[7] = [0.5, 0.5, -0.5];
    let err = tetrahedralize(&plc, &Switches::default()).unwrap_err();
    assert!(matches!(err, TetgenError::SelfIntersection { .. }), "{err}");

    // Two cubes touching in a single corner point (distinct indices).
    let (mut points, mut triangles) = cube(0.0, 1.0, 0);
    let (p2, t2) = cube(1.0, 2.0, 8);
    points.extend(p2);
    triangles.extend(t2);
    let plc = Plc {
        points,
        triangles,
        regions: Vec::new(),
    };
    let err = tetrahedralize(&plc, &Switches::default()).unwrap_err();
    assert!(
        matches!(
            err,
            TetgenError::DuplicatePoint {
                first: 7,
                second: 8
            }
        ),
        "{err}"
    );
}

#[test]
fn other_invalid_inputs_are_rejected() {
    let sw = Switches::default();
    assert_eq!(
        tetrahedralize(&Plc::default(), &sw).unwrap_err(),
        TetgenError::EmptyInput
    );

    let mut plc = unit_cube();
    plc.triangles[0][1] = 42;
    assert!(matches!(
        tetrahedralize(&plc, &sw).unwrap_err(),
        TetgenError::IndexOutOfRange {
            triangle: 0,
            index: 42,
            ..
        }
    ));

    let mut plc = unit_cube();
    plc.triangles[0] = [0, 0, 1];
    assert!(matches!(
        tetrahedralize(&plc, &sw).unwrap_err(),
        TetgenError::DegenerateTriangle { triangle: 0 }
    ));

    // Collinear triangle: move point 2 onto the segment 0-1... via a new point.
    let mut plc = unit_cube();
    plc.points.push([0.5, 0.0, 0.0]);
    plc.triangles.push([0, 1, 8]);
    assert!(matches!(
        tetrahedralize(&plc, &sw).unwrap_err(),
        TetgenError::DegenerateTriangle { triangle: 12 }
    ));

    let mut plc = unit_cube();
    plc.triangles.push(plc.triangles[3]);
    assert!(matches!(
        tetrahedralize(&plc, &sw).unwrap_err(),
        TetgenError::DuplicateTriangle {
            first: 3,
            second: 12
        }
    ));

    let mut plc = unit_cube();
    plc.points.push([5.0, 5.0, 5.0]);
    assert_eq!(
        tetrahedralize(&plc, &sw).unwrap_err(),
        TetgenError::UnusedPoint { point: 8 }
    );

    let mut plc = unit_cube();
    plc.regions.push(Region {
        seed: [0.5, 0.5, 0.0],
        attribute: 1,
        max_volume: None,
    });
    assert!(matches!(
        tetrahedralize(&plc, &sw).unwrap_err(),
        TetgenError::InvalidRegion { region: 0, .. }
    ));

    let bad = Switches {
        quality: Some(0.5),
        ..Switches::default()
    };
    assert!(matches!(
        tetrahedralize(&unit_cube(), &bad).unwrap_err(),
        TetgenError::InvalidSwitch(_)
    ));
    let bad = Switches {
        max_volume: Some(f64::NAN),
        ..Switches::default()
    };
    assert!(matches!(
        tetrahedralize(&unit_cube(), &bad).unwrap_err(),
        TetgenError::InvalidSwitch(_)
    ));
}

#[test]
fn switch_string() {
    let sw = Switches {
        quality: Some(1.414),
        min_dihedral_angle: Some(12.5),
        max_volume: Some(0.0000001),
        region_attributes: true,
        preserve_surface: true,
        max_steiner_points: Some(1000),
        quiet: true,
    };
    assert_eq!(
        sw.to_switch_string(true).unwrap(),
        "pzq1.414/12.5aa0.0000001AYS1000Q"
    );
    assert_eq!(Switches::default().to_switch_string(false).unwrap(), "pzQ");
}

fn nested_cubes(regions: Vec<Region>) -> Plc {
    let (mut points, mut triangles) = cube(0.0, 3.0, 0);
    let (inner_points, inner_triangles) = cube(1.0, 2.0, 8);
    points.extend(inner_points);
    triangles.extend(inner_triangles);
    Plc {
        points,
        triangles,
        regions,
    }
}

#[test]
fn regional_volume_without_attributes() {
    let plc = nested_cubes(vec![Region {
        seed: [1.5, 1.5, 1.5],
        attribute: 1,
        max_volume: Some(0.01),
    }]);
    let mesh = tetrahedralize(&plc, &Switches::default()).unwrap();
    assert!(mesh.tet_attributes.is_empty());
    assert_positive(&mesh);
    assert!((total_volume(&mesh) - 27.0).abs() < 1e-9);
    // The inner cube ([1, 2]^3) is refined to the regional bound.
    let inner = (0..mesh.tets.len())
        .filter(|&t| {
            let c = mesh.tets[t].iter().fold([0.0; 3], |acc, &i| {
                let p = mesh.points[i as usize];
                [
                    acc[0] + p[0] / 4.0,
                    acc[1] + p[1] / 4.0,
                    acc[2] + p[2] / 4.0,
                ]
            });
            c.iter().all(|&x| (1.0..=2.0).contains(&x))
        })
        .collect::<Vec<_>>();
    assert!(inner.len() >= 100);
    assert!(inner
        .iter()
        .all(|&t| mesh.tet_volume(t) <= 0.01 * (1.0 + 1e-9)));
}

#[test]
fn unseeded_regions_are_numbered_by_tetgen() {
    let switches = Switches {
        region_attributes: true,
        ..Switches::default()
    };
    let mesh = tetrahedralize(&nested_cubes(Vec::new()), &switches).unwrap();
    let mut seen: Vec<i32> = mesh.tet_attributes.clone();
    seen.sort_unstable();
    seen.dedup();
    assert_eq!(seen, vec![1, 2]);
}

#[test]
fn seed_outside_the_surface_is_rejected() {
    // Debian's TetGen 1.5.0 segfaults on this input if it is not caught.
    for seed in [[10.0, 1.5, 1.5], [-1.0, -1.0, -1.0], [1.5, 1.5, 3.5]] {
        let plc = nested_cubes(vec![Region {
            seed,
            attribute: 1,
            max_volume: None,
        }]);
        let err = tetrahedralize(&plc, &Switches::default()).unwrap_err();
        assert!(
            matches!(err, TetgenError::InvalidRegion { region: 0, .. }),
            "{err}"
        );
    }
    // Seeds in the cavity and in the inner cube are both inside the domain,
    // including seeds in the plane of some faces (degenerate rays are retried).
    for seed in [
        [0.5, 1.5, 1.5],
        [1.5, 1.5, 1.5],
        [1.0, 2.5, 2.5],
        [1.5, 2.0, 1.0 - 1e-12],
    ] {
        let plc = nested_cubes(vec![Region {
            seed,
            attribute: 1,
            max_volume: None,
        }]);
        tetgen_sys::validate_plc(&plc).unwrap_or_else(|e| panic!("{seed:?}: {e}"));
    }
}

/// Surface of the unit cube with every face split into an `n x n` grid of
/// squares (2 triangles each): many coplanar neighbours, which the
/// intersection test must accept.
fn subdivided_cube(n: usize) -> Plc {
    let mut points: Vec<[f64; 3]> = Vec::new();
    let mut index = std::collections::HashMap::new();
    let mut id = |p: [usize; 3], points: &mut Vec<[f64; 3]>| -> u32 {
        *index.entry(p).or_insert_with(|| {
            points.push(p.map(|c| c as f64 / n as f64));
            (points.len() - 1) as u32
        })
    };
    let mut triangles = Vec::new();
    for axis in 0..3 {
        for side in [0, n] {
            for i in 0..n {
                for j in 0..n {
                    let corner = |di: usize, dj: usize| {
                        let mut p = [0; 3];
                        p[axis] = side;
                        p[(axis + 1) % 3] = i + di;
                        p[(axis + 2) % 3] = j + dj;
                        p
                    };
                    let q = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)]
                        .map(|p| id(p, &mut points));
                    triangles.push([q[0], q[1], q[2]]);
                    triangles.push([q[0], q[2], q[3]]);
                }
            }
        }
    }
    Plc {
        points,
        triangles,
        regions: Vec::new(),
    }
}

#[test]
fn subdivided_cube_is_valid_and_meshes() {
    let plc = subdivided_cube(4);
    assert_eq!(plc.triangles.len(), 6 * 4 * 4 * 2);
    let mesh = tetrahedralize(
        &plc,
        &Switches {
            quality: Some(1.4),
            preserve_surface: true,
            ..Switches::default()
        },
    )
    .unwrap();
    assert_positive(&mesh);
    assert!((total_volume(&mesh) - 1.0).abs() < 1e-9);

    // Validation of a large surface stays fast thanks to the grid.
    let big = subdivided_cube(40); // 19 200 triangles
    let start = std::time::Instant::now();
    tetgen_sys::validate_plc(&big).unwrap();
    assert!(start.elapsed().as_secs_f64() < 10.0);

    // Pushing one face vertex through the opposite face is caught.
    let mut bad = subdivided_cube(4);
    let p = bad
        .points
        .iter()
        .position(|p| *p == [0.5, 0.5, 1.0])
        .unwrap();
    bad.points[p] = [0.5, 0.5, -0.25];
    let err = tetrahedralize(&bad, &Switches::default()).unwrap_err();
    assert!(matches!(err, TetgenError::SelfIntersection { .. }), "{err}");
}
