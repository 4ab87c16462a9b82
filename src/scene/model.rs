//! The scene model: meshes in one shared vertex/index store, the objects
//! that place them, the parts they were cut from ([`Scene`]), and the one
//! builder every loader feeds ([`SceneBuilder`]).

use std::ops::Range;
use std::path::PathBuf;

use glam::{DAffine3, DVec3};

use super::cameras::{FileAnimation, FileCamera};
use super::motion::{Mover, Route};
use super::phases::{LoadPhases, timed};
use super::up::Up;
use super::{closed, cluster, memory, validate};
use crate::bounds::Aabb;
use validate::GeometryError;

/// Default triangle budget of one cluster: meshes above it are split.
pub const DEFAULT_CLUSTER_TRIANGLES: u32 = 4096;

/// What a stored triangle costs a run, all told (its vertices and indices,
/// their copies on the GPU, the hierarchy, `swr`'s adjacency): on
/// `--scene city:blocks=32`, 24 M triangles took 1.46 GB, 61 bytes each,
/// and 1.76 GB, 73 bytes each, with `swr`'s adjacency.
const BYTES_PER_TRIANGLE: u64 = 64;

/// The most triangles a scene may store: what the memory available to
/// this process holds at [`BYTES_PER_TRIANGLE`], and never more than its
/// u32 indices can address; with the memory where that is the bound. A
/// small file can describe far more (a thousand primitives reusing one
/// accessor): refused by name, not by an allocation failing.
fn triangles_memory_allows() -> (u64, Option<u64>) {
    let address = u64::from(u32::MAX) / 3;
    match memory::available() {
        Some(bytes) if bytes / BYTES_PER_TRIANGLE < address => (bytes / BYTES_PER_TRIANGLE, Some(bytes)),
        _ => (address, None),
    }
}

/// Clusters of one mesh are stored against one origin (the centre of
/// their bounds) while those bounds span at most this many times the
/// longest side of each of them, and they are at most
/// [`SHARED_ORIGIN_CLUSTERS`]. One origin makes the clusters' shared edges
/// seamless ([`Mesh::shares_origin_with`]); a far one costs f32 precision.
/// The GPU's error in a vertex is a few steps of 2^-24 of the sums it
/// makes, |model-view · local position| + |translation|: with a span s of
/// at most 16 longest sides, and a cluster reaching at least half its
/// longest side from any eye, those sums are at most 1.7 · reach + 2 · s ≤
/// 66 · reach, so 8 steps of 2^-24 of them stay within 3.2e-5 of the
/// cluster's reach; with the rounding of the stored vertex itself (2^-24
/// of s), within 3.4e-5, below the 5e-5 by which box tests and the
/// fragment limit keep clear of its surface (gpu/conservative.rs, half of
/// `BOX_GROWTH`).
const SHARED_ORIGIN_SPAN: f64 = 16.0;

/// The most clusters stored against one origin: neighbours across them
/// are found in one sort (swr), and a run's vertices lie farther from its
/// origin the larger it is.
const SHARED_ORIGIN_CLUSTERS: usize = 64;

/// A contiguous range of the shared index buffer, its vertices a
/// contiguous run of the shared vertex buffer (a cluster's own: a vertex on
/// a cut between clusters is stored once for each). Vertex positions are
/// in a local frame whose origin lies near the mesh, so that f32 keeps its
/// precision ([`SHARED_ORIGIN_SPAN`]).
#[derive(Clone, Debug)]
pub struct Mesh {
    pub first_index: u32,
    pub index_count: u32,
    /// Bounds of the local-space vertices.
    pub bounds: Aabb,
    /// The meshes (its own among them, consecutive) cut from the same
    /// source mesh and stored against the same origin: placed by one
    /// transform, a position they share has the same f32 bits in each and
    /// so lands on the same point on the GPU, and the edges they share
    /// leave no seam.
    pub shares_origin_with: Range<u32>,
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
    /// Whether its format fixes its unit to the metre: glTF 2.0's does
    /// ("the units for all linear distances are meters"), as the built-in
    /// scenes do; an OBJ file's unit is its author's.
    pub in_metres: bool,
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

    /// The triangles of `objects` (indices into [`Scene::objects`]).
    pub fn triangles_of(&self, objects: &[u32]) -> u64 {
        objects
            .iter()
            .map(|&o| u64::from(self.objects[o as usize].triangles))
            .sum()
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
    /// How many meshes were placed by a transform that flattens them to a
    /// line or a point (they draw nothing), and the first one's name.
    flattened: (usize, Option<String>),
    warnings: Vec<String>,
    walk_hint: Option<Vec<DVec3>>,
    cameras: Vec<FileCamera>,
    animations: Vec<FileAnimation>,
    movers: Vec<Mover>,
    phases: LoadPhases,
    files: Vec<PathBuf>,
    /// The most triangles it stores, and the memory that set it (`None`:
    /// the indices' reach alone).
    most_triangles: (u64, Option<u64>),
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
            flattened: (0, None),
            warnings: Vec::new(),
            walk_hint: None,
            cameras: Vec::new(),
            animations: Vec::new(),
            movers: Vec::new(),
            phases: LoadPhases::default(),
            files: Vec::new(),
            most_triangles: triangles_memory_allows(),
        }
    }

    /// Stores at most `triangles` triangles (tests of the limit).
    #[cfg(test)]
    pub(crate) fn store_at_most(&mut self, triangles: u64) {
        self.most_triangles = (triangles, Some(triangles * BYTES_PER_TRIANGLE));
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
        let stored = (self.indices.len() + triangles.indices.len()) as u64 / 3;
        if stored > self.most_triangles.0 {
            return Err(GeometryError::TooManyTriangles {
                mesh: name.to_string(),
                triangles: stored,
                most: self.most_triangles.0,
                memory_gib: self.most_triangles.1.map(|bytes| bytes as f64 / f64::from(1 << 30)),
            });
        }
        let (closed, spent) = timed(|| closed::is_closed(positions, &triangles.indices));
        self.phases.closed_ms += spent;
        let (clusters, spent) = timed(|| self.store_clusters(positions, &triangles.indices));
        self.phases.cluster_ms += spent;
        Ok(MeshGroup { clusters, closed })
    }

    /// Splits a validated mesh into clusters and stores each as a mesh,
    /// its vertices relative to the origin of its run ([`shared_origins`]);
    /// returns (mesh id, origin).
    fn store_clusters(&mut self, positions: &[DVec3], indices: &[u32]) -> Vec<(u32, DVec3)> {
        let clusters = cluster::split(positions, indices, self.cluster_triangles);
        let first_mesh = self.meshes.len() as u32;
        let mut stored = Vec::with_capacity(clusters.len());
        for run in shared_origins(&clusters) {
            let origin = run.bounds.center();
            let meshes = first_mesh + run.clusters.start as u32..first_mesh + run.clusters.end as u32;
            for c in &clusters[run.clusters] {
                let first_index = self.indices.len() as u32;
                let base = self.vertices.len() as u32;
                self.vertices.extend(
                    c.vertices
                        .iter()
                        .map(|&v| (positions[v as usize] - origin).as_vec3().to_array()),
                );
                self.indices.extend(c.indices.iter().map(|&i| base + i));
                self.meshes.push(Mesh {
                    first_index,
                    index_count: c.indices.len() as u32,
                    bounds: Aabb::new(c.bounds.min - origin, c.bounds.max - origin),
                    shares_origin_with: meshes.clone(),
                });
                stored.push((self.meshes.len() as u32 - 1, origin));
            }
        }
        stored
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
        if flattens_to_a_line(&transform.matrix3) {
            self.flattened.0 += 1;
            self.flattened.1.get_or_insert_with(|| name.to_string());
        }
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
            let more = match self.degenerate.len().saturating_sub(3) {
                0 => String::new(),
                1 => ", and 1 more mesh".into(),
                n => format!(", and {n} more meshes"),
            };
            warnings.push(format!(
                "dropped {} ({}{more})",
                crate::text::count(dropped, "degenerate triangle"),
                worst.join(", ")
            ));
        }
        // A model of no size at all is warned of as such (above).
        let sized = bounds.extent().max_element() > 0.0;
        match self.flattened {
            (1, Some(only)) if sized => warnings.push(format!(
                "'{only}' is placed by a transform that flattens it to a line or a point: it draws nothing"
            )),
            (placed, Some(first)) if sized => warnings.push(format!(
                "{placed} meshes are placed by a transform that flattens them to a line or a point ('{first}' the first): they draw nothing"
            )),
            _ => {}
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
            in_metres: false,
            cameras: self.cameras,
            animations: self.animations,
            movers: self.movers,
            phases: self.phases,
            files: self.files,
        })
    }
}

/// Whether `linear` maps space onto a line or a point (a scale of 0 on two
/// axes, a matrix of rank below 2, or as good as one: the area it gives
/// any square, relative to its longest column squared, under 1e-12), so
/// that every triangle it places has no area. One of rank 2 flattens a
/// mesh to a plane, whose faces the GPU still draws.
fn flattens_to_a_line(linear: &glam::DMat3) -> bool {
    let [x, y, z] = [linear.x_axis, linear.y_axis, linear.z_axis];
    let longest = x.length_squared().max(y.length_squared()).max(z.length_squared());
    let area = x.cross(y).length().max(y.cross(z).length()).max(z.cross(x).length());
    area <= 1e-12 * longest
}

/// Consecutive clusters stored against one origin, and their bounds.
struct OriginRun {
    clusters: Range<usize>,
    bounds: Aabb,
}

/// `clusters` (in the split's order, so neighbours in space mostly follow
/// each other) cut into runs, each as long as its bounds span at most
/// [`SHARED_ORIGIN_SPAN`] times the longest side of each of its clusters
/// and it holds at most [`SHARED_ORIGIN_CLUSTERS`].
fn shared_origins(clusters: &[cluster::Cluster]) -> Vec<OriginRun> {
    let longest_side = |b: &Aabb| b.extent().max_element();
    let mut runs: Vec<OriginRun> = Vec::new();
    // The shortest longest side in the current run.
    let mut shortest = f64::INFINITY;
    for (k, c) in clusters.iter().enumerate() {
        let side = longest_side(&c.bounds);
        let joined = runs.last_mut().filter(|run| {
            run.clusters.len() < SHARED_ORIGIN_CLUSTERS
                && longest_side(&run.bounds.union(c.bounds)) <= SHARED_ORIGIN_SPAN * shortest.min(side)
        });
        match joined {
            Some(run) => {
                run.clusters.end = k + 1;
                run.bounds = run.bounds.union(c.bounds);
                shortest = shortest.min(side);
            }
            None => {
                runs.push(OriginRun {
                    clusters: k..k + 1,
                    bounds: c.bounds,
                });
                shortest = side;
            }
        }
    }
    runs
}

/// Triangle soup helper for generated geometry: positions and indices grow
/// together, indices relative to this soup.
#[derive(Default, Clone, Debug)]
pub struct TriangleSoup {
    pub positions: Vec<DVec3>,
    pub indices: Vec<u32>,
}

#[cfg(test)]
impl TriangleSoup {
    /// A flat grid of `columns` × `rows` squares from `corner`, spanning
    /// `across` and `down`, each square two triangles turning from
    /// `across` to `down`; corner (i, j) is vertex j · (columns + 1) + i.
    pub fn grid(corner: DVec3, across: DVec3, down: DVec3, [columns, rows]: [u32; 2]) -> TriangleSoup {
        let (step_across, step_down) = (across / f64::from(columns), down / f64::from(rows));
        let positions: Vec<DVec3> = (0..=rows)
            .flat_map(|j| (0..=columns).map(move |i| corner + step_across * f64::from(i) + step_down * f64::from(j)))
            .collect();
        let at = move |i: u32, j: u32| j * (columns + 1) + i;
        let squares = (0..rows).flat_map(move |j| (0..columns).map(move |i| (i, j)));
        let mut soup = TriangleSoup::default();
        soup.append(
            &positions,
            squares.flat_map(|(i, j)| {
                let [a, b, c, d] = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
                [a, b, c, a, c, d]
            }),
        );
        soup
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_model_past_the_triangles_memory_holds_is_refused_by_the_mesh_that_passes_it() {
        let square = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(1.0, 1.0, 0.0)];
        let mut builder = SceneBuilder::new("test".into(), 64);
        builder.store_at_most(5);
        // Two squares: 4 triangles, within 5.
        for name in ["a", "b"] {
            builder.add_mesh(name, &square, &[0, 1, 2, 2, 1, 3]).unwrap();
        }
        let third = builder
            .add_mesh("c", &square, &[0, 1, 2, 2, 1, 3])
            .unwrap_err()
            .to_string();
        assert!(
            third.starts_with("mesh 'c' brings the model to 6 triangles, more than the 5 that the"),
            "{third}"
        );
        assert!(third.ends_with("GiB of memory available holds"), "{third}");
        // Nothing of it was stored: a smaller mesh still fits.
        builder.add_mesh("d", &square, &[0, 1, 2]).unwrap();
    }

    #[test]
    fn clusters_of_one_mesh_store_a_position_they_share_with_the_same_bits_and_are_placed_alike() {
        // A grid far from the source mesh's origin (so that a cluster's own
        // centre would round its positions differently), cut into 8
        // clusters.
        let soup = TriangleSoup::grid(
            DVec3::new(1000.3, -2000.7, 5.1),
            DVec3::X * 16.0,
            DVec3::Y * 16.0,
            [16, 16],
        );
        let mut builder = SceneBuilder::new("test grid".into(), 64);
        let group = builder.add_mesh("grid", &soup.positions, &soup.indices).unwrap();
        builder
            .add_object("grid", &group, DAffine3::from_rotation_z(0.3))
            .unwrap();
        let scene = builder.finish().unwrap();
        assert_eq!(scene.objects.len(), 8);
        for (m, mesh) in scene.meshes.iter().enumerate() {
            assert_eq!(mesh.shares_origin_with, 0..8, "mesh {m}");
        }
        assert!(scene.objects.iter().all(|o| o.transform == scene.objects[0].transform));
        // Each source position is stored with one f32 value, however many
        // clusters hold it (the cuts'), and lies where the source has it.
        let mut stored: Vec<([i32; 3], [u32; 3])> = Vec::new();
        for object in &scene.objects {
            let mesh = &scene.meshes[object.mesh as usize];
            for &i in &scene.indices[mesh.first_index as usize..(mesh.first_index + mesh.index_count) as usize] {
                let local = scene.vertices[i as usize];
                let world = object.transform.transform_point3(DVec3::from(local.map(f64::from)));
                let source = DAffine3::from_rotation_z(0.3).inverse().transform_point3(world);
                stored.push((source.round().as_ivec3().to_array(), local.map(f32::to_bits)));
            }
        }
        stored.sort_unstable();
        stored.dedup();
        assert_eq!(stored.len(), 17 * 17, "one stored value per source position");
    }

    #[test]
    fn a_run_of_clusters_ends_where_its_bounds_would_span_more_than_its_reach_of_a_clusters_side() {
        let cluster = |min: DVec3, side: f64| cluster::Cluster {
            vertices: Vec::new(),
            indices: Vec::new(),
            bounds: Aabb::new(min, min + DVec3::splat(side)),
        };
        // 20 unit cubes in a row, then 72 cubes a hundredth as large, all
        // at the row's end: 16 unit cubes span the most a run may; a small
        // cube's side lets no run of unit cubes hold it; and a run holds
        // 64 clusters at most.
        let mut clusters: Vec<_> = (0..20)
            .map(|k| cluster(DVec3::new(f64::from(k), 0.0, 0.0), 1.0))
            .collect();
        clusters.extend((0..72).map(|_| cluster(DVec3::new(20.0, 0.0, 0.0), 0.01)));
        let runs: Vec<Range<usize>> = shared_origins(&clusters).into_iter().map(|r| r.clusters).collect();
        assert_eq!(runs, [0..16, 16..20, 20..84, 84..92]);
    }
}
