//! The scene model: meshes in one shared vertex/index store, the objects
//! that place them, the parts they were cut from ([`Scene`]), and the one
//! builder every loader feeds ([`SceneBuilder`]).

use std::path::PathBuf;

use glam::{DAffine3, DVec3};

use super::cameras::{FileAnimation, FileCamera};
use super::motion::{Mover, Route};
use super::phases::{LoadPhases, timed};
use super::up::Up;
use super::{closed, cluster, validate};
use crate::bounds::Aabb;
use validate::GeometryError;

/// Default triangle budget of one cluster: meshes above it are split.
pub const DEFAULT_CLUSTER_TRIANGLES: u32 = 4096;

/// A contiguous range of the shared index buffer; vertex positions are in the
/// mesh's local frame, centred on the mesh so that f32 keeps full precision.
#[derive(Clone, Debug)]
pub struct Mesh {
    pub first_index: u32,
    pub index_count: u32,
    /// Bounds of the local-space vertices.
    pub bounds: Aabb,
}

impl Mesh {
    pub fn triangles(&self) -> u32 {
        self.index_count / 3
    }
}

/// One drawable unit: a mesh placed in the world.
#[derive(Clone, Debug)]
pub struct Object {
    pub name: String,
    pub mesh: u32,
    /// Local-to-world transform, in f64 (camera-relative matrices are derived
    /// from it every frame).
    pub transform: DAffine3,
    /// World-space bounds.
    pub bounds: Aabb,
    pub triangles: u32,
    /// The [`Part`] it belongs to.
    pub part: u32,
}

/// A mesh as the loader placed it, before clustering: its objects are its
/// clusters (a glTF primitive, an OBJ object or group, a built-in piece).
#[derive(Clone, Debug)]
pub struct Part {
    pub name: String,
    /// The mesh is a closed solid ([`closed::is_closed`]): a line through
    /// it crosses its clusters' surfaces an even number of times.
    pub closed: bool,
}

#[derive(Clone, Debug)]
pub struct Scene {
    /// Where the scene came from: a file path or `builtin:NAME:PARAMS`.
    pub source: String,
    pub vertices: Vec<[f32; 3]>,
    /// Indices into `vertices` (already offset: no base vertex is needed).
    pub indices: Vec<u32>,
    pub meshes: Vec<Mesh>,
    pub objects: Vec<Object>,
    /// What each object was cut from.
    pub parts: Vec<Part>,
    pub bounds: Aabb,
    /// Problems that did not stop the load (degenerate triangles dropped, …).
    pub warnings: Vec<String>,
    /// A street-level polyline a procedural scene suggests for walks; `None`
    /// for loaded models, which get a generic walk.
    pub walk_hint: Option<Vec<DVec3>>,
    /// Objects that move from frame to frame (built-in scenes only); the
    /// objects above stand where frame 0 puts them.
    pub movers: Vec<Mover>,
    /// Which way is up, for generated paths and the overview picture.
    pub up: Up,
    /// The file's own cameras (glTF), in node order.
    pub cameras: Vec<FileCamera>,
    /// The file's animations (glTF), with the poses of the cameras they move.
    pub animations: Vec<FileAnimation>,
    /// How long each phase of loading it took.
    pub phases: LoadPhases,
    /// Every file it was read from: the model file, then a glTF file's
    /// buffer files; none for a built-in scene. No output may be one of
    /// them.
    pub files: Vec<PathBuf>,
}

impl Scene {
    pub fn triangles(&self) -> u64 {
        self.objects.iter().map(|o| u64::from(o.triangles)).sum()
    }

    /// The corners of triangle `triangle` of mesh `mesh`, in the mesh's
    /// local frame.
    pub fn triangle(&self, mesh: u32, triangle: u32) -> [DVec3; 3] {
        let first = (self.meshes[mesh as usize].first_index + 3 * triangle) as usize;
        [0, 1, 2].map(|k| DVec3::from(self.vertices[self.indices[first + k] as usize].map(f64::from)))
    }

    /// Puts every mover where `frame` has it (transform and world bounds)
    /// and appends the ids of the objects that changed to `moved`.
    pub fn pose(&mut self, frame: u32, moved: &mut Vec<u32>) {
        for mover in &self.movers {
            let transform = mover.transform(frame);
            let object = &mut self.objects[mover.object as usize];
            if object.transform != transform {
                object.transform = transform;
                object.bounds = self.meshes[object.mesh as usize].bounds.transformed(&transform);
                moved.push(mover.object);
            }
        }
    }
}

/// The clusters one source mesh was split into, ready to be instantiated.
#[derive(Clone, Debug)]
pub struct MeshGroup {
    /// (mesh id, origin of the cluster's local frame in source-mesh space).
    clusters: Vec<(u32, DVec3)>,
    /// The source mesh is a closed solid.
    closed: bool,
}

/// Accumulates validated, clustered meshes and their instances.
pub struct SceneBuilder {
    source: String,
    cluster_triangles: u32,
    vertices: Vec<[f32; 3]>,
    indices: Vec<u32>,
    meshes: Vec<Mesh>,
    objects: Vec<Object>,
    parts: Vec<Part>,
    degenerate: Vec<(String, usize)>,
    warnings: Vec<String>,
    walk_hint: Option<Vec<DVec3>>,
    cameras: Vec<FileCamera>,
    animations: Vec<FileAnimation>,
    movers: Vec<Mover>,
    phases: LoadPhases,
    files: Vec<PathBuf>,
}

impl SceneBuilder {
    pub fn new(source: String, cluster_triangles: u32) -> Self {
        SceneBuilder {
            source,
            cluster_triangles: cluster_triangles.max(1),
            vertices: Vec::new(),
            indices: Vec::new(),
            meshes: Vec::new(),
            objects: Vec::new(),
            parts: Vec::new(),
            degenerate: Vec::new(),
            warnings: Vec::new(),
            walk_hint: None,
            cameras: Vec::new(),
            animations: Vec::new(),
            movers: Vec::new(),
            phases: LoadPhases::default(),
            files: Vec::new(),
        }
    }

    /// Notes that the scene was read from `file` too (a glTF buffer file).
    pub fn read_from(&mut self, file: PathBuf) {
        self.files.push(file);
    }

    /// Validates one mesh (positions in its own frame, a triangle list) and
    /// splits it into clusters of at most `cluster_triangles` triangles.
    /// Degenerate triangles are dropped and counted; a mesh left with no
    /// triangles gives an empty group.
    pub fn add_mesh(&mut self, name: &str, positions: &[DVec3], indices: &[u32]) -> Result<MeshGroup, GeometryError> {
        // The name as the file has it; escaped where a message is shown.
        let (triangles, spent) = timed(|| validate::triangles(name, positions, indices));
        self.phases.validate_ms += spent;
        let triangles = triangles?;
        if triangles.degenerate > 0 {
            self.degenerate.push((name.to_string(), triangles.degenerate));
        }
        let (closed, spent) = timed(|| closed::is_closed(positions, &triangles.indices));
        self.phases.closed_ms += spent;
        let (clusters, spent) = timed(|| self.store_clusters(positions, &triangles.indices));
        self.phases.cluster_ms += spent;
        Ok(MeshGroup { clusters, closed })
    }

    /// Splits a validated mesh into clusters and stores each as a mesh,
    /// its vertices relative to its centre; returns (mesh id, centre).
    fn store_clusters(&mut self, positions: &[DVec3], indices: &[u32]) -> Vec<(u32, DVec3)> {
        cluster::split(positions, indices, self.cluster_triangles)
            .into_iter()
            .map(|c| {
                let first_index = self.indices.len() as u32;
                let base = self.vertices.len() as u32;
                let origin = c.bounds.center();
                self.vertices.extend(
                    c.vertices
                        .iter()
                        .map(|&v| (positions[v as usize] - origin).as_vec3().to_array()),
                );
                self.indices.extend(c.indices.iter().map(|&i| base + i));
                let local = Aabb::new(c.bounds.min - origin, c.bounds.max - origin);
                self.meshes.push(Mesh {
                    first_index,
                    index_count: c.indices.len() as u32,
                    bounds: local,
                });
                (self.meshes.len() as u32 - 1, origin)
            })
            .collect()
    }

    /// Places every cluster of `group` in the world under `transform`. A
    /// transform that is not finite or puts geometry beyond
    /// [`MAX_COORDINATE`] is an error naming the object.
    pub fn add_object(&mut self, name: &str, group: &MeshGroup, transform: DAffine3) -> Result<(), GeometryError> {
        self.place(name, group, transform).map(drop)
    }

    /// Places `group` on `route`, driven at `speed` units per frame from
    /// `start` units along it; it stands where frame 0 puts it.
    pub fn add_mover(
        &mut self,
        name: &str,
        group: &MeshGroup,
        route: &Route,
        speed: f64,
        start: f64,
    ) -> Result<(), GeometryError> {
        let first = self.place(name, group, route.placement(start))?.start;
        for (k, &(_, origin)) in group.clusters.iter().enumerate() {
            let local = DAffine3::from_translation(origin);
            let object = (first + k) as u32;
            self.movers.push(Mover::new(object, route.clone(), speed, start, local));
        }
        Ok(())
    }

    /// Adds one object per cluster of `group`; returns their ids.
    fn place(
        &mut self,
        name: &str,
        group: &MeshGroup,
        transform: DAffine3,
    ) -> Result<std::ops::Range<usize>, GeometryError> {
        let first = self.objects.len();
        let split = group.clusters.len() > 1;
        let part = self.parts.len() as u32;
        for (i, &(mesh, origin)) in group.clusters.iter().enumerate() {
            let m = &self.meshes[mesh as usize];
            let transform = transform * DAffine3::from_translation(origin);
            let bounds = m.bounds.transformed(&transform);
            if !transform.is_finite() || !validate::within_range(bounds.min) || !validate::within_range(bounds.max) {
                return Err(GeometryError::ObjectOutOfRange { object: name.into() });
            }
            self.objects.push(Object {
                name: if split { format!("{name}#{i}") } else { name.to_string() },
                mesh,
                bounds,
                transform,
                triangles: m.triangles(),
                part,
            });
        }
        self.parts.push(Part {
            name: name.to_string(),
            closed: group.closed,
        });
        Ok(first..self.objects.len())
    }

    /// Records a problem that does not stop the load; it is reported by
    /// `info` and in every result file.
    pub fn warn(&mut self, warning: String) {
        self.warnings.push(warning);
    }

    /// Records the file's cameras and animations.
    pub fn set_cameras(&mut self, cameras: Vec<FileCamera>, animations: Vec<FileAnimation>) {
        self.cameras = cameras;
        self.animations = animations;
    }

    pub fn set_walk_hint(&mut self, walk: Vec<DVec3>) {
        self.walk_hint = Some(walk);
    }

    /// The finished scene, or `None` when nothing drawable was added.
    pub fn finish(self) -> Option<Scene> {
        if self.objects.is_empty() {
            return None;
        }
        let bounds = self.objects.iter().fold(Aabb::EMPTY, |b, o| b.union(o.bounds));
        let mut warnings = self.warnings;
        warnings.extend(validate::coarse_coordinates(&bounds));
        let dropped: usize = self.degenerate.iter().map(|(_, n)| n).sum();
        if dropped > 0 {
            let worst: Vec<String> = self
                .degenerate
                .iter()
                .take(3)
                .map(|(name, n)| format!("'{name}': {n}"))
                .collect();
            let more = if self.degenerate.len() > 3 {
                format!(", and {} more meshes", self.degenerate.len() - 3)
            } else {
                String::new()
            };
            warnings.push(format!(
                "dropped {dropped} degenerate triangles ({}{more})",
                worst.join(", ")
            ));
        }
        Some(Scene {
            source: self.source,
            vertices: self.vertices,
            indices: self.indices,
            meshes: self.meshes,
            objects: self.objects,
            parts: self.parts,
            bounds,
            warnings,
            walk_hint: self.walk_hint,
            up: Up::default(),
            cameras: self.cameras,
            animations: self.animations,
            movers: self.movers,
            phases: self.phases,
            files: self.files,
        })
    }
}

/// Triangle soup helper for generated geometry: positions and indices grow
/// together, indices relative to this soup.
#[derive(Default, Clone, Debug)]
pub struct TriangleSoup {
    pub positions: Vec<DVec3>,
    pub indices: Vec<u32>,
}

impl TriangleSoup {
    pub fn triangles(&self) -> usize {
        self.indices.len() / 3
    }

    /// Appends vertices and triangles whose indices are relative to `positions`.
    pub fn append(&mut self, positions: &[DVec3], indices: impl IntoIterator<Item = u32>) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(positions);
        self.indices.extend(indices.into_iter().map(|i| base + i));
    }
}
