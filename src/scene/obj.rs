//! Wavefront OBJ: each `o`/`g` starts an object (consecutive ones of one
//! name are one), faces become triangle fans (a concave face its fan cuts
//! wrongly is counted for a warning); positions are read (a fourth number
//! `w`, finite and not 0, divides them, a colour is skipped), texture
//! coordinates and normals are only counted (faces name them), materials
//! are never read, and `l`/`p` elements, free-form curves and surfaces,
//! faces of one or two corners and lines whose statement OBJ does not
//! define are skipped and counted for a warning (a file of no faces and
//! such lines is no OBJ file, and refused). A UTF-8 byte-order mark before
//! the first line is no part of it; a line ends at `\n`, `\r\n` or a lone
//! `\r`, and one ending in a backslash continues on the next.
//!
//! Read here rather than by tobj, as it was until issue 38: tobj makes a
//! String of every line and a Vec of every face and looks every corner up
//! in a hash map, and none of its options avoids that. On the generated
//! scans of benches/load_build.rs, read in turn on the project's 2-core
//! machine, tobj took 0.37–0.49 s for 1 M triangles and 3.3–3.6 s for
//! 8 M, this reader 0.17 s and 1.35–1.5 s. It gives every file the meshes
//! tobj gave (tests/fuzz.rs holds the two against each other) but where
//! tobj misread what the specification allows or read what it should
//! refuse (`as_tobj_reads` and `joined` there list each case): an `l`
//! polyline of three or more points was a filled triangle fan there, and
//! is skipped here; tobj took a byte-order mark as part of the first line,
//! read a classic Mac OS file as one line, read each continued line alone,
//! named an indented `o` with its statement, refused `vt` with u alone and
//! a `usemtl` naming nothing, and took a w that is not finite. So, as in
//! tobj:
//! - an object's vertices are the distinct (position, texture coordinate,
//!   normal) index triples of its corners, in first-use order;
//! - indices count from 1, negative ones back from the elements read so
//!   far, and a texture coordinate or normal index of 0 means none; face
//!   indices are checked when the object ends, against everything read;
//! - a new `o`/`g` ends an object that has any face (a one- or two-corner
//!   face or an `l` too, which draw nothing), and the end of the file ends
//!   the last one however empty; consecutive objects of one name are one.

use std::collections::HashMap;
use std::path::Path;

use glam::{DAffine3, DVec3};

use super::memory;
use super::model::SceneBuilder;
use super::source::{LoadOptions, SceneError};
use crate::text::count;

/// Loads an OBJ model. The options on reading further files do not apply:
/// an OBJ file's geometry is all in it, and its material files are not read.
pub fn load(path: &Path, bytes: &[u8], _: &LoadOptions, builder: &mut SceneBuilder) -> Result<(), SceneError> {
    let invalid = |message| SceneError::Parse {
        path: path.into(),
        message: format!("invalid OBJ: {message}"),
    };
    // Read only as far as the memory available holds while it is read,
    // which takes more per triangle than the model built from it keeps.
    let most_triangles = memory::available().map_or(u64::MAX, |bytes| bytes / READ_BYTES_PER_TRIANGLE);
    let obj = parse(bytes, most_triangles).map_err(invalid)?;
    let warnings = judge(&obj).map_err(invalid)?;
    for object in &obj.objects {
        let geometry = |error| SceneError::Geometry {
            path: path.into(),
            error,
        };
        let group = builder
            .add_mesh(&object.name, &object.positions, &object.indices)
            .map_err(geometry)?;
        builder
            .add_object(&object.name, &group, DAffine3::IDENTITY)
            .map_err(geometry)?;
    }
    for warning in warnings {
        builder.warn(warning);
    }
    Ok(())
}

/// What reading an OBJ file takes per triangle of its faces, at most: its
/// corners, the face they come from and the objects made of them (a 2 M
/// triangle grid, 57 MB of text, took 284 MB at the peak of `occlu info`,
/// 142 bytes a triangle with the text; a face of 3 M corners, 133 bytes a
/// corner), and the room its vectors reserve as they grow, which an
/// address-space limit counts (under `ulimit -v 250000` that grid aborted
/// at 160 bytes a triangle).
const READ_BYTES_PER_TRIANGLE: u64 = 256;

/// What an OBJ file holds for occlu.
struct Obj {
    objects: Vec<Object>,
    /// `l` and `p` elements.
    skipped: usize,
    /// Free-form curves and surfaces (`curv`, `curv2`, `surf`).
    free_form: usize,
    /// Faces of one or two corners, which draw nothing.
    short_faces: usize,
    /// Faces whose fan covers what they do not ([`Reader::fan_covers_outside`]).
    fanned_outside: usize,
    unknown: Unknown,
}

/// Lines whose statement OBJ does not define (a typo such as `F` or `vv`,
/// a legacy one such as `fo`, or a file that is not OBJ at all): how many,
/// and the first.
#[derive(Default)]
struct Unknown {
    lines: usize,
    first: Option<(usize, String)>,
}

/// Every statement of the OBJ format (Wavefront's specification, version
/// 3.0, with the superseded ones its appendix still lists) that occlu
/// reads nothing from: free-form geometry's attributes and body (its
/// elements, `curv`, `curv2` and `surf`, are counted), grouping, display
/// and rendering attributes. A line that starts with none of these, nor
/// one read, is unknown.
const IGNORED_STATEMENTS: &[&str] = &[
    "vp",
    "cstype",
    "deg",
    "bmat",
    "step",
    "parm",
    "trim",
    "hole",
    "scrv",
    "sp",
    "end",
    "con",
    "s",
    "mg",
    "bevel",
    "c_interp",
    "d_interp",
    "lod",
    "usemtl",
    "mtllib",
    "usemap",
    "maplib",
    "shadow_obj",
    "trace_obj",
    "ctech",
    "stech",
    "call",
    "csh",
    "bsp",
    "bzp",
    "cdc",
    "cdp",
    "res",
];

/// Characters of an unknown statement a warning quotes.
const STATEMENT_SHOWN: usize = 40;

/// What the file's statements say of it beyond its geometry: the warnings
/// of what it drew nothing from, or an error where it has no faces and
/// lines whose statement OBJ does not define.
fn judge(obj: &Obj) -> Result<Vec<String>, String> {
    let mut warnings = Vec::new();
    if obj.skipped > 0 {
        warnings.push(format!(
            "ignored {} line/point elements ('l'/'p'): only faces are rendered",
            obj.skipped
        ));
    }
    if obj.free_form > 0 {
        warnings.push(format!(
            "ignored {} ('curv', 'curv2', 'surf'): only faces are rendered",
            count(obj.free_form, "free-form curve or surface")
        ));
    }
    if obj.short_faces > 0 {
        warnings.push(format!(
            "ignored {} of one or two corners: they enclose nothing to draw",
            count(obj.short_faces, "face")
        ));
    }
    if obj.fanned_outside > 0 {
        warnings.push(format!(
            "fanned {} from a first corner that does not see all of the face, as tobj did: the triangles cover more than the face",
            count(obj.fanned_outside, "concave face")
        ));
    }
    if let Some((line, statement)) = &obj.unknown.first {
        let mut shown: String = statement.chars().take(STATEMENT_SHOWN).collect();
        if shown.len() < statement.len() {
            shown.push('…');
        }
        let what = format!(
            "{} whose statement OBJ does not define (the first, line {line}: '{shown}')",
            count(obj.unknown.lines, "line")
        );
        if obj.objects.iter().all(|o| o.indices.is_empty()) {
            return Err(format!("no faces, and {what}: is it an OBJ file?"));
        }
        warnings.push(format!("ignored {what}"));
    }
    Ok(warnings)
}

struct Object {
    name: String,
    positions: Vec<DVec3>,
    /// Triangles, as indices into `positions`.
    indices: Vec<u32>,
}

/// A face corner's position, texture coordinate and normal, counted from
/// 0; [`NONE`] where the corner names none.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
struct Corner {
    v: usize,
    vt: usize,
    vn: usize,
}

/// No element: what an index of 0 (or one counting back to just before
/// the first element) comes to, as in tobj.
const NONE: usize = usize::MAX;

/// A corner's indices as the file wrote them (0 where it names none), for
/// a message about one that names nothing: a negative index resolved too
/// far back no longer says what was written.
type Written = [isize; 3];

fn parse(bytes: &[u8], most_triangles: u64) -> Result<Obj, String> {
    if bytes.starts_with(b"glTF") {
        return Err("a GLB file (it starts with the bytes 'glTF'), not OBJ: name it .glb".into());
    }
    let text = std::str::from_utf8(bytes).map_err(|e| format!("not UTF-8 text (byte {})", e.valid_up_to()))?;
    // A byte-order mark (Windows editors write one) is no part of the first
    // line: read as one, it hid that line's statement, and a first vertex
    // lost shifted every face's indices.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut reader = Reader {
        name: "unnamed_object".into(),
        most_triangles,
        ..Reader::default()
    };
    // A line ending in a backslash continues on the next (the
    // specification's line continuation): the statement is read whole, as
    // of its first line. A comment continues nothing.
    let mut statement = String::new();
    let mut continued_from = None;
    for (number, line) in lines(text).enumerate() {
        let body = line
            .trim_end()
            .strip_suffix('\\')
            .filter(|_| !line.trim_start().starts_with('#'));
        match (continued_from, body) {
            (None, None) => {
                reader.line = number + 1;
                reader.read_line(line)?;
            }
            (_, Some(body)) => {
                continued_from.get_or_insert(number + 1);
                statement.push_str(body);
                statement.push(' ');
            }
            (Some(first), None) => {
                statement.push_str(line);
                reader.line = first;
                reader.read_line(&statement)?;
                statement.clear();
                continued_from = None;
            }
        }
    }
    if let Some(first) = continued_from {
        reader.line = first;
        reader.read_line(&statement)?;
    }
    reader.end_object()?;
    Ok(Obj {
        objects: reader.objects,
        skipped: reader.skipped,
        free_form: reader.free_form,
        short_faces: reader.short_faces,
        fanned_outside: reader.fanned_outside,
        unknown: reader.unknown,
    })
}

#[derive(Default)]
struct Reader {
    /// The line being read, from 1.
    line: usize,
    /// The most triangles it may hold ([`READ_BYTES_PER_TRIANGLE`]), and
    /// those its faces have made so far (a face being read counted for
    /// those its corners so far make).
    most_triangles: u64,
    triangles: u64,
    /// Every `v` so far.
    positions: Vec<DVec3>,
    /// Colour components given with positions (a face's vertex must have
    /// one, once any has: tobj's rule).
    colour_values: usize,
    texcoords: usize,
    normals: usize,
    /// The object being read: its name, its triangles' corners, whether
    /// any names a texture coordinate or normal, whether it has any face.
    name: String,
    corners: Vec<Corner>,
    with_attributes: bool,
    has_faces: bool,
    /// Its corners that named an element not read yet (or none that
    /// exists), with their lines and indices as written: checked when it
    /// ends.
    unresolved: Vec<(usize, Corner, Written)>,
    /// One face's corners, before they are cut into triangles, and their
    /// indices as written.
    face: Vec<Corner>,
    face_written: Vec<Written>,
    /// The object's vertex of each position so far (`u32::MAX`: none),
    /// while its corners are gathered.
    vertex_of: Vec<u32>,
    objects: Vec<Object>,
    skipped: usize,
    free_form: usize,
    short_faces: usize,
    fanned_outside: usize,
    unknown: Unknown,
}

impl Reader {
    /// `message`, at the line being read.
    fn fail(&self, message: impl std::fmt::Display) -> String {
        format!("line {}: {message}", self.line)
    }

    /// Reads `line`: its words as `split_whitespace` finds them, byte by
    /// byte where the line is ASCII (almost every line of almost every
    /// file).
    fn read_line(&mut self, line: &str) -> Result<(), String> {
        if line.is_ascii() {
            self.read(line, ascii_words(line))
        } else {
            self.read(line, line.split_whitespace())
        }
    }

    /// Reads `line`, split into `words`.
    fn read<'a>(&mut self, line: &str, mut words: impl Iterator<Item = &'a str>) -> Result<(), String> {
        match words.next() {
            Some("v") => self.vertex(words)?,
            // u, then v where given (the specification's default is 0);
            // what follows is not read, as after a normal's three numbers.
            Some("vt") => {
                let (u, v) = (words.next().map(str::parse::<f64>), words.next().map(str::parse::<f64>));
                if !matches!(u, Some(Ok(_))) || matches!(v, Some(Err(_))) {
                    return Err(self.fail("a texture coordinate needs a number u, and v a number where given"));
                }
                self.texcoords += 1;
            }
            Some("vn") => {
                numbers::<3>(&mut words).ok_or_else(|| self.fail("a normal needs three numbers"))?;
                self.normals += 1;
            }
            Some("f") => self.face(words)?,
            Some("l") => {
                self.skipped += 1;
                self.has_faces = true;
            }
            Some("p") => self.skipped += 1,
            Some("curv" | "curv2" | "surf") => self.free_form += 1,
            Some("o" | "g") => {
                if self.has_faces {
                    self.end_object()?;
                }
                // The rest of the line after the statement, spaces and all.
                let statement = line.trim_start();
                self.name = match statement[1..].trim() {
                    "" => "unnamed_object".into(),
                    name => name.into(),
                };
            }
            Some(statement) if !statement.starts_with('#') && !IGNORED_STATEMENTS.contains(&statement) => {
                self.unknown.lines += 1;
                // Kept as far as it is shown (a file of one 2 GB line is
                // one statement).
                let kept = || (self.line, statement.chars().take(STATEMENT_SHOWN + 1).collect());
                self.unknown.first.get_or_insert_with(kept);
            }
            _ => {}
        }
        Ok(())
    }

    fn vertex<'a>(&mut self, mut words: impl Iterator<Item = &'a str>) -> Result<(), String> {
        let position = numbers::<3>(&mut words).ok_or_else(|| self.fail("a vertex needs three numbers"))?;
        let mut position = DVec3::from_array(position);
        match (words.next(), words.next(), words.next(), words.next()) {
            (None, ..) => {}
            (Some(w), None, ..) => match w.parse::<f64>() {
                Ok(0.0) => return Err(self.fail("a vertex's w is 0")),
                Ok(w) if !w.is_finite() => return Err(self.fail(format_args!("a vertex's w '{w}' is not finite"))),
                Ok(w) => position /= w,
                Err(_) => return Err(self.fail(format_args!("a vertex's w '{w}' is not a number"))),
            },
            // A colour: its components up to the first that is not a
            // number count.
            (Some(r), Some(g), Some(b), None) => {
                self.colour_values += [r, g, b].iter().take_while(|c| c.parse::<f64>().is_ok()).count();
            }
            _ => return Err(self.fail("a vertex has three numbers, and a w or a colour")),
        }
        self.positions.push(position);
        Ok(())
    }

    fn face<'a>(&mut self, words: impl Iterator<Item = &'a str>) -> Result<(), String> {
        self.face.clear();
        self.face_written.clear();
        for word in words {
            let (corner, written) = self
                .corner(word)
                .ok_or_else(|| self.fail(format_args!("face corner '{word}' is not v, v/vt, v//vn or v/vt/vn")))?;
            self.face.push(corner);
            self.face_written.push(written);
            if self.triangles + (self.face.len() as u64).saturating_sub(2) > self.most_triangles {
                return Err(self.fail(format_args!(
                    "its faces pass {} triangles, more than the memory available holds while they are read",
                    self.most_triangles
                )));
            }
        }
        self.has_faces = true;
        match self.face.as_slice() {
            [] => return Err(self.fail("a face without corners")),
            // A point or a line: nothing to draw.
            [_] | [_, _] => self.short_faces += 1,
            [first, rest @ ..] => {
                self.triangles += rest.len() as u64 - 1;
                for pair in rest.windows(2) {
                    self.corners.extend([*first, pair[0], pair[1]]);
                }
                if self.fan_covers_outside() {
                    self.fanned_outside += 1;
                }
                // Whether an index names none (0 as written: an index that
                // counts back one too far resolves to NONE too) or one read.
                let named = |index: usize, written: isize, count: usize| written == 0 || index < count;
                for (&corner, &written) in self.face.iter().zip(&self.face_written) {
                    let vt = named(corner.vt, written[1], self.texcoords);
                    let vn = named(corner.vn, written[2], self.normals);
                    if !(corner.v < self.positions.len() && vt && vn) {
                        self.unresolved.push((self.line, corner, written));
                    }
                    self.with_attributes |= written[1] != 0 || written[2] != 0;
                }
            }
        }
        Ok(())
    }

    /// Whether the fan from the face's first corner, which cuts it into
    /// triangles as tobj and most readers cut a face, covers what the face
    /// does not: a fan triangle turns against the face (its Newell normal),
    /// by more than a millionth of the face's area, as where a concave
    /// face is cut from a corner that does not see all of it. A face
    /// naming a position not read yet is not judged.
    fn fan_covers_outside(&self) -> bool {
        let n = self.face.len();
        let at = |k: usize| self.positions.get(self.face[k % n].v).copied();
        let turns_against = || -> Option<bool> {
            let mut normal = DVec3::ZERO;
            for k in 0..n {
                let (p, q) = (at(k)?, at(k + 1)?);
                normal += DVec3::new(
                    (p.y - q.y) * (p.z + q.z),
                    (p.z - q.z) * (p.x + q.x),
                    (p.x - q.x) * (p.y + q.y),
                );
            }
            let first = at(0)?;
            let least = -1e-6 * normal.length_squared();
            for k in 1..n - 1 {
                if (at(k)? - first).cross(at(k + 1)? - first).dot(normal) < least {
                    return Some(true);
                }
            }
            Some(false)
        };
        n > 3 && turns_against() == Some(true)
    }

    /// A corner `v`, `v/vt`, `v//vn` or `v/vt/vn`, its indices resolved
    /// against the elements read so far, and as written. Out of range they
    /// wrap, as in tobj, and fail the check when the object ends.
    fn corner(&self, word: &str) -> Option<(Corner, Written)> {
        let counts = [self.positions.len(), self.texcoords, self.normals];
        let resolve = |k: usize, i: isize| {
            if i < 0 {
                (counts[k] as isize).wrapping_add(i) as usize
            } else {
                i.wrapping_sub(1) as usize
            }
        };
        let mut written = [0; 3];
        if word.contains('/') {
            for (k, part) in word.split('/').enumerate().filter(|(_, part)| !part.is_empty()) {
                *written.get_mut(k)? = part.parse().ok()?;
            }
        } else {
            written[0] = word.parse().ok()?;
        }
        let index = |k: usize| if written[k] == 0 { NONE } else { resolve(k, written[k]) };
        let corner = Corner {
            v: index(0),
            vt: index(1),
            vn: index(2),
        };
        Some((corner, written))
    }

    /// Ends the object being read: its faces' indices checked against
    /// everything read, its vertices gathered, appended to the previous
    /// object when that has the same name.
    fn end_object(&mut self) -> Result<(), String> {
        for &(line, corner, written) in &self.unresolved {
            self.check(corner, written).map_err(|e| format!("line {line}: {e}"))?;
        }
        if self.colour_values > 0 {
            for &corner in &self.corners {
                if corner.v * 3 + 2 >= self.colour_values {
                    return Err(format!(
                        "object '{}': a face names vertex {}, which has no colour where earlier ones have",
                        self.name,
                        corner.v + 1
                    ));
                }
            }
        }
        let mut by_triple = HashMap::with_hasher(foldhash::fast::FixedState::default());
        if !self.with_attributes {
            self.vertex_of.resize(self.positions.len(), u32::MAX);
        }
        let mut used = Vec::new();
        let mut indices = Vec::with_capacity(self.corners.len());
        for &corner in &self.corners {
            // Without texture coordinates or normals, a triple is its
            // position: an array finds it faster than a map.
            let vertex = if self.with_attributes {
                by_triple.entry(corner).or_insert(u32::MAX)
            } else {
                &mut self.vertex_of[corner.v]
            };
            if *vertex == u32::MAX {
                *vertex = used.len() as u32;
                used.push(corner.v);
            }
            indices.push(*vertex);
        }
        if !self.with_attributes {
            for &v in &used {
                self.vertex_of[v] = u32::MAX;
            }
        }
        let positions = used.iter().map(|&v| self.positions[v]);
        match self.objects.last_mut() {
            Some(last) if last.name == self.name => {
                let base = last.positions.len() as u32;
                last.positions.extend(positions);
                last.indices.extend(indices.iter().map(|&i| base + i));
            }
            _ => self.objects.push(Object {
                name: self.name.clone(),
                positions: positions.collect(),
                indices,
            }),
        }
        self.corners.clear();
        self.unresolved.clear();
        self.with_attributes = false;
        self.has_faces = false;
        Ok(())
    }

    /// That `corner` (`written` so) names elements that exist (a texture
    /// coordinate or normal only where the file has any).
    fn check(&self, corner: Corner, written: Written) -> Result<(), String> {
        let missing =
            |what: &str, written: isize, count: usize| Err(format!("a face names {what} {written} of {count}"));
        if corner.v >= self.positions.len() {
            return missing("vertex", written[0], self.positions.len());
        }
        for (what, index, written, count) in [
            ("texture coordinate", corner.vt, written[1], self.texcoords),
            ("normal", corner.vn, written[2], self.normals),
        ] {
            if count > 0 && written != 0 && index >= count {
                return missing(what, written, count);
            }
        }
        Ok(())
    }
}

/// The lines of `text`, each ended by `\n`, `\r\n` or a lone `\r`
/// (classic Mac OS files: read as one line, such a file lost every
/// statement after its first).
fn lines(text: &str) -> impl Iterator<Item = &str> {
    let mut rest = text;
    std::iter::from_fn(move || {
        if rest.is_empty() {
            return None;
        }
        let bytes = rest.as_bytes();
        let (line, next) = match memchr::memchr2(b'\n', b'\r', bytes) {
            Some(end) => {
                let crlf = bytes[end] == b'\r' && bytes.get(end + 1) == Some(&b'\n');
                (&rest[..end], &rest[end + 1 + usize::from(crlf)..])
            }
            None => (rest, ""),
        };
        rest = next;
        Some(line)
    })
}

/// The words of an ASCII `line`: what `split_whitespace` gives, found
/// without decoding characters.
fn ascii_words(line: &str) -> impl Iterator<Item = &str> {
    let bytes = line.as_bytes();
    bytes
        .split(|b| *b == b' ' || (b'\t'..=b'\r').contains(b))
        .filter(|word| !word.is_empty())
        .map(move |word| {
            let start = word.as_ptr() as usize - bytes.as_ptr() as usize;
            &line[start..start + word.len()]
        })
}

/// The next `N` words as numbers, if they are.
fn numbers<'a, const N: usize>(words: &mut impl Iterator<Item = &'a str>) -> Option<[f64; N]> {
    let mut values = [0.0; N];
    for value in &mut values {
        *value = words.next()?.parse().ok()?;
    }
    Some(values)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ascii_words_are_the_words_split_whitespace_finds() {
        let whitespace = [" ", "\t", "\n", "\u{b}", "\u{c}", "\r", "  "];
        let mut line = String::new();
        for (k, gap) in whitespace.iter().cycle().take(40).enumerate() {
            line += gap;
            line += &format!("w{k}");
            line += ["", "/", "-1", "e5"][k % 4];
        }
        line += "\u{b} ";
        let expected: Vec<&str> = line.split_whitespace().collect();
        assert_eq!(ascii_words(&line).collect::<Vec<_>>(), expected);
        assert_eq!(expected.len(), 40);
        assert_eq!(ascii_words(" \t\u{b}").count(), 0);
    }

    #[test]
    fn errors_name_the_line_and_what_is_wrong() {
        let error = |text: &str| parse(text.as_bytes(), u64::MAX).err().unwrap();
        assert_eq!(error("v 0 0 0\nv 1 0\n"), "line 2: a vertex needs three numbers");
        assert_eq!(
            error("v 0 0 0\n\nf 1 2 x\n"),
            "line 3: face corner 'x' is not v, v/vt, v//vn or v/vt/vn"
        );
        // Checked when the object ends, against everything read by then.
        assert_eq!(
            error("f 1 2 3\nv 0 0 0\nv 1 0 0\no b\n"),
            "line 1: a face names vertex 3 of 2"
        );
        assert!(
            parse(b"f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n", u64::MAX).is_ok(),
            "named before given"
        );
        assert_eq!(
            error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -4 1 2\n"),
            "line 4: a face names vertex -4 of 3",
            "as written, not as counted back"
        );
        assert_eq!(
            error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -9\n"),
            "line 4: a face names vertex -9 of 3"
        );
        assert_eq!(
            error("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//-2 3//1\n"),
            "line 5: a face names normal -2 of 1"
        );
        assert_eq!(
            error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"),
            "line 4: a face names vertex 0 of 3"
        );
        assert_eq!(error("v 0 0 0 0\n"), "line 1: a vertex's w is 0");
        assert_eq!(
            parse(b"v 0 0 \xff\n", u64::MAX).err().unwrap(),
            "not UTF-8 text (byte 6)"
        );
    }

    /// A hostile-input review's finding: a face of 99 M corners (198 MB of
    /// text) aborted for memory while it was read.
    #[test]
    fn faces_past_the_triangles_memory_holds_are_refused_while_they_are_read() {
        let text = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 1 2 4 3\n";
        assert_eq!(parse(text, 3).map(|obj| obj.objects[0].indices.len()), Ok(9));
        let refused = parse(text, 2).err().unwrap();
        assert_eq!(
            refused,
            "line 6: its faces pass 2 triangles, more than the memory available holds while they are read"
        );
        let unknown = format!("{}\n", "x".repeat(1 << 20));
        let (_, kept) = parse(unknown.as_bytes(), u64::MAX).unwrap().unknown.first.unwrap();
        assert_eq!(
            kept.len(),
            STATEMENT_SHOWN + 1,
            "an unknown statement is kept as far as it is shown"
        );
    }

    #[test]
    fn a_byte_order_mark_is_no_part_of_the_first_line() {
        let text = "v 0 0 0\nv 10 0 0\nv 0 10 0\nv 0 0 10\nf 1 2 3\nf 2 3 4\n";
        let with_mark = format!("\u{feff}{text}");
        let (plain, marked) = (
            parse(text.as_bytes(), u64::MAX).unwrap(),
            parse(with_mark.as_bytes(), u64::MAX).unwrap(),
        );
        assert_eq!(marked.objects[0].positions, plain.objects[0].positions);
        assert_eq!(marked.objects[0].indices, plain.objects[0].indices);
        assert_eq!(marked.unknown.lines, 0);
    }

    #[test]
    fn statements_obj_does_not_have_and_faces_that_draw_nothing_are_warned_of() {
        let text =
            "# a comment\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvv 5 5 5\ns off\nf 1 2 3\nF 2 3 4\nfo 1 2 4\nf 1 2\n";
        let obj = parse(text.as_bytes(), u64::MAX).unwrap();
        assert_eq!(obj.objects[0].indices, [0, 1, 2]);
        assert_eq!(
            judge(&obj).unwrap(),
            [
                "ignored 1 face of one or two corners: they enclose nothing to draw",
                "ignored 3 lines whose statement OBJ does not define (the first, line 6: 'vv')",
            ]
        );
        // A line continued by a backslash starts no statement of its own.
        let clean = parse(
            b"mtllib a.mtl\nusemtl red\nv 0 0 0\nv 1 0 0\nv 0 1 0\ng x\nf 1 2 3\nparm u 0 \\\n 0.5 1\n",
            u64::MAX,
        )
        .unwrap();
        assert!(judge(&clean).unwrap().is_empty());
    }

    #[test]
    fn what_the_specification_allows_and_tobj_refused_loads() {
        let unix = "o plate\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.5\nusemtl red\nf 1/1 2/1 3/1\n";
        let expected = parse(unix.replace("vt 0.5", "vt 0.5 0").as_bytes(), u64::MAX).unwrap();
        for (what, text) in [
            ("old Mac OS line endings", unix.replace('\n', "\r")),
            ("a tab before the material", unix.replace("usemtl ", "usemtl\t")),
            ("an indented statement", unix.replace("o plate", "  o plate")),
            ("Windows line endings", unix.replace('\n', "\r\n")),
        ] {
            let obj = parse(text.as_bytes(), u64::MAX).unwrap_or_else(|e| panic!("{what}: {e}"));
            assert_eq!(obj.objects.len(), 1, "{what}");
            assert_eq!(obj.objects[0].name, "plate", "{what}");
            assert_eq!(obj.objects[0].positions, expected.objects[0].positions, "{what}");
            assert_eq!(obj.objects[0].indices, expected.objects[0].indices, "{what}");
        }
        let error = |text: &str| parse(text.as_bytes(), u64::MAX).err().unwrap();
        let needs = "a texture coordinate needs a number u, and v a number where given";
        assert_eq!(error("vt\n"), format!("line 1: {needs}"));
        assert_eq!(error("vt 0 x\n"), format!("line 1: {needs}"));
        assert!(parse(b"vt 0 0 x\n", u64::MAX).is_ok(), "w is not read");
        assert_eq!(error("v 0 0 1 inf\n"), "line 1: a vertex's w 'inf' is not finite");
        assert_eq!(
            error("glTF\u{2}\0\0\0"),
            "a GLB file (it starts with the bytes 'glTF'), not OBJ: name it .glb"
        );
        assert_eq!(error("v 0 0 0\rv 1 0\r"), "line 2: a vertex needs three numbers");
    }

    #[test]
    fn continued_lines_are_one_statement_and_free_form_geometry_is_warned_of() {
        let plain = parse(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", u64::MAX).unwrap();
        for text in [
            // A face continued, a statement OBJ has continued over a
            // vertex-like line, and a continuation at the end of the file.
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 \\\n3\n",
            "parm u 0 \\\nv 9 9 9\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nparm u 0 \\",
            // A comment continues nothing; an empty usemtl names nothing.
            "# note \\\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl\nf 1 2 3\n",
        ] {
            let obj = parse(text.as_bytes(), u64::MAX).unwrap_or_else(|e| panic!("{text:?}: {e}"));
            assert_eq!(obj.objects[0].positions, plain.objects[0].positions, "{text:?}");
            assert_eq!(obj.objects[0].indices, plain.objects[0].indices, "{text:?}");
            assert_eq!(obj.unknown.lines, 0, "{text:?}");
        }
        let surface =
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\ncstype bezier\ndeg 1 1\nsurf 0 1 0 1 1 2 3 1\nparm u 0 1\nend\n";
        assert_eq!(
            judge(&parse(surface.as_bytes(), u64::MAX).unwrap()).unwrap(),
            ["ignored 1 free-form curve or surface ('curv', 'curv2', 'surf'): only faces are rendered"]
        );
    }

    #[test]
    fn a_concave_face_cut_from_a_corner_that_does_not_see_it_all_is_warned_of() {
        // An L of six corners in the plane z = 0.
        let l_shape = "v 1 1 0\nv 1 2 0\nv 0 2 0\nv 0 0 0\nv 2 0 0\nv 2 1 0\n";
        let fanned = |face: &str| judge(&parse(format!("{l_shape}{face}\n").as_bytes(), u64::MAX).unwrap()).unwrap();
        // From a corner beside the notch, the last triangle spans it.
        assert_eq!(
            fanned("f 2 3 4 5 6 1"),
            [
                "fanned 1 concave face from a first corner that does not see all of the face, as tobj did: the triangles cover more than the face"
            ]
        );
        // From its reflex corner, which sees all of it, every fan triangle
        // lies inside.
        assert!(fanned("f 1 2 3 4 5 6").is_empty());
        // A square, and a square with a corner on an edge, are convex.
        assert!(fanned("f 4 5 6 3").is_empty());
        assert!(
            judge(&parse(b"v 0 0 0\nv 1 0 0\nv 2 0 0\nv 2 2 0\nv 0 2 0\nf 1 2 3 4 5\n", u64::MAX).unwrap())
                .unwrap()
                .is_empty()
        );
    }

    #[test]
    fn a_file_with_no_faces_and_statements_obj_does_not_have_is_not_taken_for_an_empty_model() {
        let gltf = parse(b"{\n  \"asset\": {\"version\": \"2.0\"}\n}\n", u64::MAX).unwrap();
        assert_eq!(
            judge(&gltf).unwrap_err(),
            "no faces, and 3 lines whose statement OBJ does not define (the first, line 1: '{'): is it an OBJ file?"
        );
    }
}
