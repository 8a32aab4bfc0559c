//! VTK XML output (`.vtu` unstructured grids and `.vtp` polydata) through
//! `vtkio`, for inspecting meshes and interfaces in ParaView.
//!
//! Files are written in the VTK XML format version 1.0 with inline
//! base64-encoded binary arrays (little endian, `UInt64` headers), which
//! VTK ≥ 9 / ParaView ≥ 5.8 read with their standard XML readers. Points are
//! always 3D; use [`points_2d_to_3d`] for 2D meshes (z = 0). All writes are
//! atomic (see [`crate::io::write_atomic`]).

use std::path::Path;

use vtkio::model::{
    Attribute, Attributes, ByteOrder, CellType, DataArray, DataSet, ElementType, IOBuffer, Piece,
    PolyDataPiece, UnstructuredGridPiece, Version, VertexNumbers, Vtk,
};

use super::atomic::write_atomic;
use super::error::{IoError, Result};

/// The cells of an unstructured grid: all triangles (2D meshes) or all
/// tetrahedra (3D meshes), as indices into the point array.
#[derive(Clone, Copy, Debug)]
pub enum Cells<'a> {
    /// Triangles (VTK cell type 5).
    Triangles(&'a [[u32; 3]]),
    /// Tetrahedra (VTK cell type 10).
    Tetrahedra(&'a [[u32; 4]]),
}

impl Cells<'_> {
    /// Number of cells.
    pub fn len(&self) -> usize {
        match self {
            Cells::Triangles(t) => t.len(),
            Cells::Tetrahedra(t) => t.len(),
        }
    }

    /// Whether there are no cells.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// One value per cell, attached as a named scalar cell-data array
/// (e.g. `("phase", CellArray::I32(&labels))`).
#[derive(Clone, Copy, Debug)]
pub enum CellArray<'a> {
    /// Integer data such as phase labels (VTK `Int32`).
    I32(&'a [i32]),
    /// Real data such as mean intensities or quality measures (VTK `Float64`).
    F64(&'a [f64]),
}

impl CellArray<'_> {
    fn len(&self) -> usize {
        match self {
            CellArray::I32(v) => v.len(),
            CellArray::F64(v) => v.len(),
        }
    }

    fn to_buffer(self) -> IOBuffer {
        match self {
            CellArray::I32(v) => IOBuffer::I32(v.to_vec()),
            CellArray::F64(v) => IOBuffer::F64(v.to_vec()),
        }
    }
}

/// Lifts 2D points to 3D with `z = 0`, for writing 2D meshes.
pub fn points_2d_to_3d(points: &[[f64; 2]]) -> Vec<[f64; 3]> {
    points.iter().map(|&[x, y]| [x, y, 0.0]).collect()
}

/// Writes an XML unstructured grid (`.vtu`) with the given points, cells and
/// named cell-data arrays (each must have one value per cell).
pub fn write_vtu(
    path: impl AsRef<Path>,
    points: &[[f64; 3]],
    cells: Cells<'_>,
    cell_data: &[(&str, CellArray<'_>)],
) -> Result<()> {
    let path = path.as_ref();
    let (connectivity, offsets, types) = match cells {
        Cells::Triangles(t) => {
            let (c, o) = flatten(path, points.len(), t)?;
            (c, o, vec![CellType::Triangle; t.len()])
        }
        Cells::Tetrahedra(t) => {
            let (c, o) = flatten(path, points.len(), t)?;
            (c, o, vec![CellType::Tetra; t.len()])
        }
    };
    let piece = UnstructuredGridPiece {
        points: flat_points(points),
        cells: vtkio::model::Cells {
            cell_verts: VertexNumbers::XML {
                connectivity,
                offsets,
            },
            types,
        },
        data: attributes(path, cells.len(), cell_data)?,
    };
    let data = DataSet::UnstructuredGrid {
        meta: None,
        pieces: vec![Piece::Inline(Box::new(piece))],
    };
    write_vtk(path, data)
}

/// Writes XML polydata (`.vtp`) made of triangles with named cell-data
/// arrays; used for interface surfaces (e.g. arrays `phase` and
/// `phase_other` holding the phases on both sides of each triangle).
pub fn write_vtp(
    path: impl AsRef<Path>,
    points: &[[f64; 3]],
    triangles: &[[u32; 3]],
    cell_data: &[(&str, CellArray<'_>)],
) -> Result<()> {
    let path = path.as_ref();
    let (connectivity, offsets) = flatten(path, points.len(), triangles)?;
    let piece = PolyDataPiece {
        points: flat_points(points),
        polys: Some(VertexNumbers::XML {
            connectivity,
            offsets,
        }),
        data: attributes(path, triangles.len(), cell_data)?,
        ..Default::default()
    };
    let data = DataSet::PolyData {
        meta: None,
        pieces: vec![Piece::Inline(Box::new(piece))],
    };
    write_vtk(path, data)
}

/// Writes XML polydata (`.vtp`) made of line segments with named cell-data
/// arrays; used for 2D interfaces (arrays `phase` and `phase_other`).
pub fn write_vtp_lines(
    path: impl AsRef<Path>,
    points: &[[f64; 3]],
    segments: &[[u32; 2]],
    cell_data: &[(&str, CellArray<'_>)],
) -> Result<()> {
    let path = path.as_ref();
    let (connectivity, offsets) = flatten(path, points.len(), segments)?;
    let piece = PolyDataPiece {
        points: flat_points(points),
        lines: Some(VertexNumbers::XML {
            connectivity,
            offsets,
        }),
        data: attributes(path, segments.len(), cell_data)?,
        ..Default::default()
    };
    let data = DataSet::PolyData {
        meta: None,
        pieces: vec![Piece::Inline(Box::new(piece))],
    };
    write_vtk(path, data)
}

/// Flattens the points into the `x y z x y z ...` buffer VTK expects.
fn flat_points(points: &[[f64; 3]]) -> IOBuffer {
    IOBuffer::F64(points.iter().flatten().copied().collect())
}

/// Checks the indices and builds XML connectivity and (end) offsets.
fn flatten<const N: usize>(
    path: &Path,
    num_points: usize,
    cells: &[[u32; N]],
) -> Result<(Vec<u64>, Vec<u64>)> {
    let mut connectivity = Vec::with_capacity(N * cells.len());
    for (c, cell) in cells.iter().enumerate() {
        for &v in cell {
            if v as usize >= num_points {
                return Err(IoError::invalid(
                    path,
                    format!("cell {c} uses point {v} but there are {num_points} points"),
                ));
            }
            connectivity.push(u64::from(v));
        }
    }
    let offsets = (1..=cells.len()).map(|i| (i * N) as u64).collect();
    Ok((connectivity, offsets))
}

/// Builds the cell attributes, checking one value per cell.
fn attributes(
    path: &Path,
    num_cells: usize,
    cell_data: &[(&str, CellArray<'_>)],
) -> Result<Attributes> {
    let mut cell = Vec::with_capacity(cell_data.len());
    for (name, array) in cell_data {
        if array.len() != num_cells {
            return Err(IoError::invalid(
                path,
                format!(
                    "cell array {name:?} has {} values for {num_cells} cells",
                    array.len()
                ),
            ));
        }
        cell.push(Attribute::DataArray(DataArray {
            name: (*name).to_string(),
            elem: ElementType::Scalars {
                num_comp: 1,
                lookup_table: None,
            },
            data: array.to_buffer(),
        }));
    }
    Ok(Attributes {
        point: Vec::new(),
        cell,
    })
}

/// Serialises a data set as VTK XML into `path`, atomically.
fn write_vtk(path: &Path, data: DataSet) -> Result<()> {
    let vtk = Vtk {
        version: Version::new_xml(1, 0),
        title: String::new(),
        byte_order: ByteOrder::LittleEndian,
        data,
        file_path: None,
    };
    write_atomic(path, |w| vtk.write_xml(w).map_err(std::io::Error::other))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reads a file back with vtkio and returns (points, cells, cell array names).
    fn read_back(path: &Path) -> (usize, usize, Vec<String>) {
        let vtk = Vtk::import(path).unwrap();
        let names = |a: &Attributes| a.cell.iter().map(|c| c.name().to_string()).collect();
        match vtk.data {
            DataSet::UnstructuredGrid { pieces, .. } => match &pieces[0] {
                Piece::Inline(p) => (p.num_points(), p.cells.types.len(), names(&p.data)),
                _ => panic!("not inline"),
            },
            DataSet::PolyData { pieces, .. } => match &pieces[0] {
                Piece::Inline(p) => (p.num_points(), p.num_polys(), names(&p.data)),
                _ => panic!("not inline"),
            },
            _ => panic!("unexpected data set"),
        }
    }

    /// Writes one file of each kind into `dir`; also used to feed
    /// `.ci/check_vtk.py` (set `DSC_SEG_VTK_OUT` to keep them).
    fn write_samples(dir: &Path) -> [std::path::PathBuf; 3] {
        let pts2 = points_2d_to_3d(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
        let tris = [[0, 1, 2], [0, 2, 3]];
        let a = dir.join("tri.vtu");
        write_vtu(
            &a,
            &pts2,
            Cells::Triangles(&tris),
            &[
                ("phase", CellArray::I32(&[0, 1])),
                ("mean", CellArray::F64(&[0.25, 0.75])),
            ],
        )
        .unwrap();
        let pts3 = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
        ];
        let tets = [[0, 1, 2, 3], [1, 2, 3, 4]];
        let b = dir.join("tet.vtu");
        write_vtu(
            &b,
            &pts3,
            Cells::Tetrahedra(&tets),
            &[("phase", CellArray::I32(&[1, 2]))],
        )
        .unwrap();
        let c = dir.join("surface.vtp");
        write_vtp(
            &c,
            &pts3,
            &[[1, 2, 3]],
            &[
                ("phase", CellArray::I32(&[1])),
                ("phase_other", CellArray::I32(&[2])),
            ],
        )
        .unwrap();
        [a, b, c]
    }

    #[test]
    fn vtu_and_vtp_read_back() {
        let tmp = tempfile::tempdir().unwrap();
        let keep = std::env::var_os("DSC_SEG_VTK_OUT").map(std::path::PathBuf::from);
        let dir = keep.as_deref().unwrap_or(tmp.path());
        let [a, b, c] = write_samples(dir);
        assert_eq!(read_back(&a), (4, 2, vec!["phase".into(), "mean".into()]));
        assert_eq!(read_back(&b), (5, 2, vec!["phase".into()]));
        assert_eq!(
            read_back(&c),
            (5, 1, vec!["phase".into(), "phase_other".into()])
        );
        let text = std::fs::read_to_string(&a).unwrap();
        assert!(text.contains("UnstructuredGrid") && text.contains("Name=\"phase\""));
    }

    #[test]
    fn invalid_input_is_rejected() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bad.vtu");
        let pts = [[0.0; 3]; 3];
        let e = write_vtu(&p, &pts, Cells::Triangles(&[[0, 1, 3]]), &[]).unwrap_err();
        assert!(e.to_string().contains("bad.vtu"));
        let e = write_vtp(
            &p,
            &pts,
            &[[0, 1, 2]],
            &[("phase", CellArray::I32(&[1, 2]))],
        );
        assert!(e.is_err());
        assert!(!p.exists());
    }
}
