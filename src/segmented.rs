//! A finished segmentation held in memory: the label image, the final mesh
//! as plain arrays and the report, and the writer of the command line's
//! output files.
//!
//! The command line (one input or a batch) and the Python package both go
//! through [`crate::pipeline::segment_image`] /
//! [`crate::pipeline::segment_volume`] and this type, so their labels and
//! files are the same by construction.

use crate::complex::{Complex2, Complex3};
use crate::error::{Error, Result};
use crate::io::resolution::{is_tiff, millimetres_per, Resolution};
use crate::io::{
    save_gray8_png, save_gray8_png_with_pixel_size, save_labels_nifti, save_labels_tiff,
    write_bytes_atomic, write_pvd, write_vti, write_vtm,
};
use crate::io::{Frame, FrameSource, Image2, Overlay};
use crate::segment::measurements::Measurements;
use crate::segment::SegmentReport;
use crate::staging::Staging;
use std::path::Path;
use std::time::Instant;

/// A finished 2D or 3D segmentation.
#[derive(Clone, Debug)]
pub struct Segmented {
    /// The input's size: `[width, height]` or `[nx, ny, nz]`.
    pub dims: Vec<usize>,
    /// Phase index per pixel/voxel (0..N-1 by increasing mean), x fastest:
    /// row-major `height × width`, or `nz × ny × nx`.
    pub labels: Vec<u8>,
    /// Vertex positions of the final mesh, 2 (2D) or 3 (3D) per vertex, in
    /// the mesh's own units: pixels in 2D, the volume's length unit in 3D
    /// (see [`Segmented::physical_vertices`]).
    pub vertices: Vec<f64>,
    /// The mesh's triangles (3 vertex indices each) or tetrahedra (4).
    pub cells: Vec<u32>,
    /// Each cell's phase index (as in `labels`).
    pub cell_phases: Vec<u8>,
    /// The run's summary (iterations, convergence, energies, timings).
    pub summary: SegmentReport,
    /// Everything `report.json` holds (its `times.write` is set when written).
    pub report: serde_json::Value,
    /// Where the input's pixels/voxels sit in the world (the VTK files' frame).
    pub frame: Frame,
    /// Per-phase and per-interface figures in physical units.
    pub measurements: Measurements,
    pub(crate) render: Render,
    /// A 2D TIFF input: the labels are also written as `labels.tif`, with
    /// the input's pixel size.
    pub(crate) tiff_labels: bool,
}

/// What the writers need beyond the arrays.
#[derive(Clone, Debug)]
pub(crate) enum Render {
    /// An image.
    Image {
        /// The segmented image as the overlay shows it.
        shown: Image2,
        /// Its values in the file's units (as `report.json` gives the
        /// means), for `image.vti`: a viewer's probe and colour bar must read
        /// what the file holds, not the loaded `[0, 1]` scale.
        values: Vec<f32>,
        /// The final complex.
        complex: Box<Complex2>,
        /// The rank of each mesh label.
        order: Vec<u8>,
        /// The header of a NIfTI slice: the labels are also written as
        /// NIfTI with its geometry (`labels.nii.gz`).
        nifti_header: Option<Vec<u8>>,
    },
    /// A volume.
    Volume {
        /// Its values in the file's units, for `image.vti`.
        values: Option<Vec<f32>>,
        /// The final complex.
        complex: Box<Complex3>,
        /// The rank of each mesh label.
        order: Vec<u8>,
        /// The header of a NIfTI input: the labels are written as NIfTI
        /// with its geometry (`labels.nii.gz`).
        nifti_header: Option<Vec<u8>>,
    },
}

/// The label map of a NIfTI input.
const NIFTI_LABELS: &str = "labels.nii.gz";

/// The output files a run writes; `--outputs` chooses among them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Outputs {
    /// `labels.png` (2D) or `labels.tif` (3D).
    pub labels: bool,
    /// `overlay.png` and `overlay.svg` (2D only).
    pub overlay: bool,
    /// `mesh.vtu`.
    pub mesh: bool,
    /// `interface.vtp`.
    pub interface: bool,
    /// `image.vti`, the input in the VTK files' frame.
    pub image: bool,
    /// `phases.csv` and `interfaces.csv`.
    pub phases: bool,
    /// `report.json`.
    pub report: bool,
}

impl Default for Outputs {
    fn default() -> Self {
        Self::ALL
    }
}

impl Outputs {
    /// Every output.
    pub const ALL: Outputs = Outputs {
        labels: true,
        overlay: true,
        mesh: true,
        interface: true,
        image: true,
        phases: true,
        report: true,
    };

    /// Parses `--outputs`: a comma-separated list of `labels`, `overlay`
    /// (2D), `mesh`, `interface` (3D), `report`, or `all`.
    pub fn parse(list: &str, three_d: bool) -> Result<Self> {
        let mut o = Outputs {
            labels: false,
            overlay: false,
            mesh: false,
            interface: false,
            image: false,
            phases: false,
            report: false,
        };
        let names = if three_d {
            "labels, mesh, interface, image, phases, report or all"
        } else {
            "labels, overlay, mesh, interface, image, phases, report or all"
        };
        for name in list.split(',').map(str::trim) {
            match name {
                "labels" => o.labels = true,
                "overlay" if !three_d => o.overlay = true,
                "mesh" => o.mesh = true,
                "interface" => o.interface = true,
                "image" => o.image = true,
                "phases" => o.phases = true,
                "report" => o.report = true,
                "all" => o = Self::ALL,
                _ => {
                    return Err(Error::Usage(format!(
                        "--outputs {list:?}: unknown output {name:?} (each one of {names})"
                    )))
                }
            }
        }
        Ok(o)
    }

    /// The VTK files among these outputs (listed by `scene.vtm` and `scene.pvd`).
    pub fn vtk_files(&self) -> Vec<&'static str> {
        let mut f = Vec::new();
        if self.image {
            f.push("image.vti");
        }
        if self.mesh {
            f.push("mesh.vtu");
        }
        if self.interface {
            f.push("interface.vtp");
        }
        f
    }

    /// The file names these outputs are, in 2D or 3D, `report.json` last;
    /// `scene.vtm` and `scene.pvd` come with any VTK file.
    pub fn files(&self, three_d: bool) -> Vec<&'static str> {
        let mut f = Vec::new();
        if self.labels {
            f.push(if three_d { "labels.tif" } else { "labels.png" });
        }
        if self.overlay && !three_d {
            f.extend(["overlay.png", "overlay.svg"]);
        }
        let vtk = self.vtk_files();
        if !vtk.is_empty() {
            f.extend(vtk);
            f.extend(["scene.vtm", "scene.pvd"]);
        }
        if self.phases {
            f.extend(["phases.csv", "interfaces.csv"]);
        }
        if self.report {
            f.push("report.json");
        }
        f
    }

    /// Files in `dir` that a run with other outputs would have written and
    /// this one does not: left from an earlier run, they no longer match
    /// the new results beside them. Listed, not removed: `dir` may be a
    /// folder of the user's own files with the same names.
    pub fn earlier_outputs(&self, three_d: bool, dir: &Path) -> Vec<&'static str> {
        let mut written = self.files(three_d);
        if self.labels {
            written.extend(["labels.tif", NIFTI_LABELS]);
        }
        let mut all = Outputs::ALL.files(three_d);
        all.extend(["labels.tif", NIFTI_LABELS]);
        all.sort_unstable();
        all.dedup();
        all.into_iter()
            .filter(|name| !written.contains(name) && dir.join(name).is_file())
            .collect()
    }

    /// [`files`](Self::files) as a run on `input` writes them: a NIfTI
    /// volume's labels are `labels.nii.gz` instead of `labels.tif`, and a 2D
    /// TIFF's labels come as `labels.tif` too, a NIfTI slice's as
    /// `labels.nii.gz`.
    pub fn files_for(&self, three_d: bool, input: &Path) -> Vec<&'static str> {
        let mut f = self.files(three_d);
        if three_d && crate::io::volume::is_nifti(input) {
            for name in &mut f {
                if *name == "labels.tif" {
                    *name = NIFTI_LABELS;
                }
            }
        } else if !three_d && self.labels && is_tiff(input) {
            f.insert(1, "labels.tif");
        } else if !three_d && self.labels && crate::io::volume::is_nifti(input) {
            f.insert(1, NIFTI_LABELS);
        }
        f
    }
}

impl Segmented {
    /// Whether this is a 3D segmentation.
    pub fn is_3d(&self) -> bool {
        self.dims.len() == 3
    }

    /// [`Segmented::vertices`] in the input's physical units (the frame's
    /// spacing per pixel/voxel) from the outer corner of pixel/voxel 0, along
    /// the index axes: a 2D mesh, which works in pixels, is scaled by the
    /// pixel size; a 3D mesh already works in these units.
    pub fn physical_vertices(&self) -> Vec<f64> {
        let d = self.dims.len();
        let scale: Vec<f64> = (0..d)
            .map(|c| self.frame.spacing[c] / self.frame.domain_scale[c])
            .collect();
        self.vertices
            .chunks_exact(d)
            .flat_map(|p| p.iter().zip(&scale).map(|(x, s)| x * s))
            .collect()
    }

    /// Writes `outputs` into `dir` (created if missing), all or nothing.
    pub fn write(&self, dir: &Path, outputs: &Outputs) -> Result<()> {
        self.write_staged(Staging::new(dir)?, dir, outputs)
    }

    /// Writes `outputs` into `stage` and publishes them into `dir`.
    pub(crate) fn write_staged(&self, stage: Staging, dir: &Path, outputs: &Outputs) -> Result<()> {
        let t_write = Instant::now();
        let path = |name: &str| stage.path().join(name);
        let frame = &self.frame;
        match &self.render {
            Render::Image { shown, .. } => {
                // The overlay beside the other files: it takes longest.
                let (overlay, files) = rayon::join(
                    || {
                        if outputs.overlay {
                            self.write_overlay(shown, &path)
                        } else {
                            Ok(())
                        }
                    },
                    || self.write_2d_files(&path, outputs),
                );
                overlay?;
                files?;
            }
            Render::Volume {
                values,
                complex,
                order,
                nifti_header,
            } => {
                if let (true, Some(header)) = (outputs.labels, nifti_header) {
                    let phases = self.measurements.phases.len();
                    save_labels_nifti(path(NIFTI_LABELS), header, &self.labels, phases)?;
                } else if outputs.labels {
                    let d = [self.dims[0], self.dims[1], self.dims[2]];
                    let resolution = Resolution {
                        spacing: frame.spacing,
                        unit: frame.unit.clone(),
                    };
                    save_labels_tiff(path("labels.tif"), d, &self.labels, Some(&resolution))?;
                }
                if outputs.mesh {
                    complex.write_mesh_vtu(path("mesh.vtu"), order, frame)?;
                }
                if outputs.interface {
                    complex.write_interface_vtp(path("interface.vtp"), order, frame)?;
                }
                if outputs.image {
                    let values = values.as_deref().ok_or_else(|| {
                        Error::Usage("image.vti needs the volume's values".into())
                    })?;
                    write_vti(path("image.vti"), frame, "intensity", values)?;
                }
            }
        }
        let vtk = outputs.vtk_files();
        if !vtk.is_empty() {
            write_vtm(path("scene.vtm"), &vtk)?;
            write_pvd(path("scene.pvd"), &vtk)?;
        }
        if outputs.phases {
            let d = self.dims.len();
            let m = &self.measurements;
            write_bytes_atomic(path("phases.csv"), m.phases_csv(d).as_bytes())?;
            write_bytes_atomic(path("interfaces.csv"), m.interfaces_csv(d).as_bytes())?;
        }
        if outputs.report {
            let mut report = self.report.clone();
            if let Some(times) = report.get_mut("times") {
                times["write"] = t_write.elapsed().as_secs_f64().into();
            }
            let json =
                serde_json::to_vec_pretty(&report).map_err(|e| Error::Usage(e.to_string()))?;
            write_bytes_atomic(path("report.json"), &json)?;
        }
        let mut files = outputs.files(self.is_3d());
        if let Render::Volume {
            nifti_header: Some(_),
            ..
        } = &self.render
        {
            for f in &mut files {
                if *f == "labels.tif" {
                    *f = NIFTI_LABELS;
                }
            }
        }
        if self.tiff_labels && outputs.labels {
            files.insert(1, "labels.tif");
        }
        if let (
            Render::Image {
                nifti_header: Some(_),
                ..
            },
            true,
        ) = (&self.render, outputs.labels)
        {
            files.insert(1, NIFTI_LABELS);
        }
        stage.publish(dir, &files)
    }

    /// An image's files but the overlay: its labels (and their NIfTI for a
    /// NIfTI slice), `mesh.vtu`, `interface.vtp` and `image.vti`, as chosen.
    fn write_2d_files(
        &self,
        path: &(dyn Fn(&str) -> std::path::PathBuf + Sync),
        outputs: &Outputs,
    ) -> Result<()> {
        let Render::Image {
            values,
            complex,
            order,
            nifti_header,
            ..
        } = &self.render
        else {
            return Ok(());
        };
        let frame = &self.frame;
        self.write_2d_labels(path, outputs)?;
        if let (true, Some(header)) = (outputs.labels, nifti_header) {
            let phases = self.measurements.phases.len();
            save_labels_nifti(path(NIFTI_LABELS), header, &self.labels, phases)?;
        }
        if outputs.mesh {
            complex.write_mesh_vtu(path("mesh.vtu"), order, frame)?;
        }
        if outputs.interface {
            complex.write_interface_vtp(path("interface.vtp"), order, frame)?;
        }
        if outputs.image {
            write_vti(path("image.vti"), frame, "intensity", values)?;
        }
        Ok(())
    }

    /// `labels.png` and, for a TIFF input, `labels.tif`.
    fn write_2d_labels(
        &self,
        path: &(dyn Fn(&str) -> std::path::PathBuf + Sync),
        outputs: &Outputs,
    ) -> Result<()> {
        let (w, h) = (self.dims[0], self.dims[1]);
        if outputs.labels {
            // The input's pixel size, when it had one in a length unit.
            let mm = millimetres_per(&self.frame.unit)
                .filter(|_| self.frame.source != FrameSource::Default);
            if let Some(mm) = mm {
                let [sx, sy, _] = self.frame.spacing;
                let size = [sx * mm, sy * mm];
                save_gray8_png_with_pixel_size(path("labels.png"), (w, h), &self.labels, size)?;
            } else {
                save_gray8_png(path("labels.png"), w, h, &self.labels)?;
            }
            if self.tiff_labels {
                let resolution = (self.frame.source != FrameSource::Default).then(|| Resolution {
                    spacing: self.frame.spacing,
                    unit: self.frame.unit.clone(),
                });
                save_labels_tiff(
                    path("labels.tif"),
                    [w, h, 1],
                    &self.labels,
                    resolution.as_ref(),
                )?;
            }
        }
        Ok(())
    }

    /// `overlay.png` and `overlay.svg`, written on two threads. The PNG,
    /// drawn at least 768 pixels wide (twice a 512² image's size, three
    /// times a 256² one's), is the most expensive of a 2D run's outputs (on
    /// a 512² four-phase image more instructions than the segmentation); the
    /// SVG embeds the image at its own size and draws the rest as vectors.
    fn write_overlay(
        &self,
        image: &Image2,
        path: &(dyn Fn(&str) -> std::path::PathBuf + Sync),
    ) -> Result<()> {
        let points: Vec<[f64; 2]> = self
            .vertices
            .chunks_exact(2)
            .map(|p| [p[0], p[1]])
            .collect();
        let tris: Vec<[u32; 3]> = self
            .cells
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect();
        let phase: Vec<u32> = self.cell_phases.iter().map(|&p| p as u32).collect();
        let overlay = Overlay::new(image, &points, &tris, &phase).readable();
        let (png, svg) = rayon::join(
            || overlay.to_png(path("overlay.png")),
            || overlay.to_svg(path("overlay.svg")),
        );
        png?;
        Ok(svg?)
    }
}
