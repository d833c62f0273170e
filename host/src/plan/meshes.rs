//! The collision meshes of a URDF: where a `<mesh filename>` is (`package://PKG/..` searched in
//! the package paths and in the URDF's own folders, `file://`, relative to the URDF, absolute)
//! and its vertices (STL, binary or ASCII, read by `stl_io`).

use std::path::{Path, PathBuf};

use nalgebra::Point3;

use super::PlanError;

/// Largest mesh file read, bytes (a collision mesh is small: the Panda's are 10-15 kB).
pub const MAX_MESH_BYTES: u64 = 64 << 20;

/// Where `filename` (as written in the URDF at `urdf_path`) is: `package://PKG/REST` in
/// `package_paths` (each as `DIR/PKG/REST`, or `DIR/REST` when DIR is named PKG) and then in
/// the URDF's own folders (an ancestor named PKG); `file://` and absolute paths as they are;
/// other paths relative to the URDF's folder. Errors name every place tried.
pub fn resolve_mesh(
    filename: &str,
    urdf_path: &Path,
    package_paths: &[PathBuf],
) -> Result<PathBuf, PlanError> {
    let urdf_dir = urdf_path.parent().unwrap_or(Path::new("."));
    let mut tried: Vec<PathBuf> = Vec::new();
    if let Some(rest) = filename.strip_prefix("package://") {
        let (pkg, rel) = rest.split_once('/').unwrap_or((rest, ""));
        for dir in package_paths {
            tried.push(dir.join(pkg).join(rel));
            if dir.file_name().is_some_and(|n| n == pkg) {
                tried.push(dir.join(rel));
            }
        }
        let abs = std::fs::canonicalize(urdf_dir).unwrap_or_else(|_| urdf_dir.to_path_buf());
        for anc in abs.ancestors() {
            if anc.file_name().is_some_and(|n| n == pkg) {
                tried.push(anc.join(rel));
            }
            tried.push(anc.join(pkg).join(rel));
        }
    } else if let Some(p) = filename.strip_prefix("file://") {
        tried.push(PathBuf::from(p));
    } else {
        let p = Path::new(filename);
        tried.push(if p.is_absolute() {
            p.to_path_buf()
        } else {
            urdf_dir.join(p)
        });
    }
    if let Some(found) = tried.iter().find(|p| p.is_file()) {
        return Ok(found.clone());
    }
    let shown: Vec<String> = tried
        .iter()
        .take(8)
        .map(|p| p.display().to_string())
        .collect();
    Err(PlanError::Geometry(format!(
        "collision mesh `{filename}` of {} not found (tried {}{}); give --package-path DIR or set ROS_PACKAGE_PATH",
        urdf_path.display(),
        shown.join(", "),
        if tried.len() > 8 { ", ..." } else { "" }
    )))
}

/// Whether `path` is an STL file by its extension.
pub fn is_stl(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("stl"))
}

/// The vertices of the STL file `path` (binary or ASCII), each multiplied by `scale_mm` (the
/// URDF scale times 1000: metres to mm).
pub fn stl_vertices_mm(path: &Path, scale_mm: [f64; 3]) -> Result<Vec<Point3<f64>>, PlanError> {
    let err = |m: String| PlanError::Geometry(format!("collision mesh {}: {m}", path.display()));
    let len = std::fs::metadata(path)
        .map_err(|e| err(e.to_string()))?
        .len();
    if len > MAX_MESH_BYTES {
        return Err(err(format!("{len} bytes, more than {MAX_MESH_BYTES}")));
    }
    let bytes = std::fs::read(path).map_err(|e| err(e.to_string()))?;
    let mesh = stl_io::read_stl(&mut std::io::Cursor::new(bytes))
        .map_err(|e| err(format!("not a readable STL file: {e}")))?;
    let pts: Vec<Point3<f64>> = mesh
        .vertices
        .iter()
        .map(|v| {
            Point3::new(
                f64::from(v[0]) * scale_mm[0],
                f64::from(v[1]) * scale_mm[1],
                f64::from(v[2]) * scale_mm[2],
            )
        })
        .collect();
    if pts.len() < 4 || pts.iter().any(|p| !p.coords.iter().all(|c| c.is_finite())) {
        return Err(err(format!(
            "{} vertices: a mesh needs at least 4 finite ones",
            pts.len()
        )));
    }
    Ok(pts)
}

#[cfg(test)]
mod tests {
    use super::*;

    const TETRA_ASCII: &str = "solid t
facet normal 0 0 -1
 outer loop
  vertex 0 0 0
  vertex 1 0 0
  vertex 0 1 0
 endloop
endfacet
facet normal 0 -1 0
 outer loop
  vertex 0 0 0
  vertex 0 0 1
  vertex 1 0 0
 endloop
endfacet
endsolid t
";

    #[test]
    fn resolves_packages_and_reads_ascii_and_binary_stl() {
        let dir = tempfile::tempdir().unwrap();
        let pkg = dir.path().join("share/mypkg");
        std::fs::create_dir_all(pkg.join("meshes")).unwrap();
        std::fs::create_dir_all(pkg.join("urdf")).unwrap();
        let ascii = pkg.join("meshes/a.stl");
        std::fs::write(&ascii, TETRA_ASCII).unwrap();
        let urdf = pkg.join("urdf/r.urdf");
        // by the URDF's own folders, by --package-path, relative
        let found = resolve_mesh("package://mypkg/meshes/a.stl", &urdf, &[]).unwrap();
        assert!(found.ends_with("mypkg/meshes/a.stl"));
        let other = tempfile::tempdir().unwrap();
        let via = resolve_mesh(
            "package://mypkg/meshes/a.stl",
            &other.path().join("x.urdf"),
            &[dir.path().join("share")],
        )
        .unwrap();
        assert!(via.is_file());
        assert!(resolve_mesh("../meshes/a.stl", &urdf, &[]).is_ok());
        let missing = resolve_mesh("package://nopkg/m.stl", &urdf, &[]).unwrap_err();
        assert!(missing.to_string().contains("--package-path"));
        let v = stl_vertices_mm(&ascii, [1000.0; 3]).unwrap();
        assert_eq!(v.len(), 4);
        assert!(v.iter().any(|p| p.z == 1000.0));
        // the same triangles written as binary STL
        let mesh = stl_io::read_stl(&mut std::io::Cursor::new(TETRA_ASCII)).unwrap();
        let tris: Vec<stl_io::Triangle> = mesh
            .faces
            .iter()
            .map(|f| stl_io::Triangle {
                normal: f.normal,
                vertices: f.vertices.map(|i| mesh.vertices[i]),
            })
            .collect();
        let bin = pkg.join("meshes/b.stl");
        let mut out = std::fs::File::create(&bin).unwrap();
        stl_io::write_stl(&mut out, tris.iter()).unwrap();
        drop(out);
        let w = stl_vertices_mm(&bin, [2.0, 2.0, 2.0]).unwrap();
        assert_eq!(w.len(), 4);
        assert!(w.iter().any(|p| p.x == 2.0));
        std::fs::write(&bin, b"garbage").unwrap();
        assert!(stl_vertices_mm(&bin, [1.0; 3]).is_err());
    }
}
