//! Malformed input never panics and gives `Error::Io` naming the file and the problem:
//! truncations at many points, garbage, wrong counts, indices out of range, bit flips.

mod io_common;

use io_common::{Lcg, grid, put, scratch};
use std::path::Path;
use toothfuse::ErrorKind;
use toothfuse::io::{PlyEncoding, VtpEncoding, read_mesh, write_mesh_with, write_vtp};

/// Valid files of every format (name, bytes), small enough to cut at every few bytes.
fn samples(d: &Path) -> Vec<(String, Vec<u8>)> {
    let m = grid(6, 9);
    let lab: Vec<i32> = (0..m.vertex_count() as i32).collect();
    let cl: Vec<i32> = (0..m.face_count() as i32).collect();
    let mut out = Vec::new();
    for (name, enc) in [
        ("bin.ply", PlyEncoding::BinaryLittleEndian),
        ("be.ply", PlyEncoding::BinaryBigEndian),
        ("ascii.ply", PlyEncoding::Ascii),
    ] {
        let p = d.join(name);
        write_mesh_with(&p, &m, &[("label", &lab)], enc).unwrap();
        out.push((name.to_string(), std::fs::read(&p).unwrap()));
    }
    for name in ["a.stl", "a.obj"] {
        let p = d.join(name);
        toothfuse::io::write_mesh(&p, &m, &[]).unwrap();
        out.push((name.to_string(), std::fs::read(&p).unwrap()));
    }
    let encs = [
        VtpEncoding::Ascii,
        VtpEncoding::Binary {
            compressed: true,
            header64: false,
        },
        VtpEncoding::AppendedRaw {
            compressed: true,
            header64: true,
        },
        VtpEncoding::AppendedRaw {
            compressed: false,
            header64: false,
        },
        VtpEncoding::AppendedBase64 {
            compressed: true,
            header64: false,
        },
    ];
    for (i, enc) in encs.into_iter().enumerate() {
        let mut b = Vec::new();
        write_vtp(&mut b, &m, &[("label", &lab)], &[("Label", &cl)], enc).unwrap();
        out.push((format!("v{i}.vtp"), b));
    }
    out.push(("a.vtk".into(), LEGACY.as_bytes().to_vec()));
    out
}

const LEGACY: &str = "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 4 float\n\
0 0 0 1 0 0 1 1 0 0 1 0\nPOLYGONS 2 8\n3 0 1 2\n3 0 2 3\nCELL_DATA 2\nSCALARS label int\n\
LOOKUP_TABLE default\n11 12\n";

fn expect_io(p: &Path, must_contain: &[&str]) -> String {
    let e = read_mesh(p).expect_err(&format!("{} should fail", p.display()));
    assert_eq!(e.kind(), ErrorKind::Io, "{e}");
    let s = e.to_string();
    for m in must_contain {
        assert!(s.contains(m), "{:?} not in {s:?}", m);
    }
    s
}

#[test]
fn truncated_files_never_panic_and_mid_cuts_fail() {
    let d = scratch("trunc");
    for (name, bytes) in samples(&d) {
        assert!(read_mesh(put(&d, &name, &bytes)).is_ok(), "{name} intact");
        for cut in (0..bytes.len()).step_by(17) {
            let p = put(&d, &name, &bytes[..cut]);
            if let Err(e) = read_mesh(&p) {
                assert_eq!(e.kind(), ErrorKind::Io, "{name} cut at {cut}: {e}");
                assert!(
                    e.to_string().contains(&name),
                    "{name}: message names the file: {e}"
                );
            }
        }
        // Cutting the file in half always loses data, detectably in every format with counts
        // (OBJ has none: a cut at a line end is a smaller valid OBJ).
        if name.ends_with(".obj") {
            continue;
        }
        for cut in [bytes.len() / 4, bytes.len() / 2, 3 * bytes.len() / 5] {
            expect_io(&put(&d, &name, &bytes[..cut]), &[&name]);
        }
    }
}

#[test]
fn garbage_and_bit_flips_never_panic() {
    let d = scratch("garbage");
    let mut r = Lcg(42);
    for ext in ["ply", "stl", "obj", "vtp", "vtk"] {
        for len in [0usize, 1, 5, 83, 84, 134, 500, 4000] {
            let bytes: Vec<u8> = (0..len).map(|_| (r.next() * 256.0) as u8).collect();
            let p = put(&d, &format!("g.{ext}"), &bytes);
            if ext != "obj" {
                // A random OBJ without `v`/`f` records is an empty mesh, not an error.
                expect_io(&p, &["g."]);
            } else {
                let _ = read_mesh(&p);
            }
        }
    }
    // Flip bytes in valid files: any outcome but a panic; errors are Io.
    for (name, bytes) in samples(&d) {
        for k in 0..60 {
            let mut b = bytes.clone();
            let i = (r.next() * b.len() as f64) as usize;
            b[i] ^= 1 << (k % 8);
            if let Err(e) = read_mesh(put(&d, &name, &b)) {
                assert_eq!(e.kind(), ErrorKind::Io, "{name}: {e}");
            }
        }
    }
}

#[test]
fn indices_out_of_range_are_named() {
    let d = scratch("oob");
    let ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
        property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n\
        0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 2 7\n";
    expect_io(
        &put(&d, "o.ply", ply.as_bytes()),
        &["face 1 refers to vertex 7", "3 vertices"],
    );
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n";
    expect_io(
        &put(&d, "o.obj", obj.as_bytes()),
        &["face 1 refers to vertex 8", "line 5"],
    );
    let obj = "v 0 0 0\nf -1 -2 -3\n";
    expect_io(&put(&d, "n.obj", obj.as_bytes()), &["refers to vertex -1"]);
    let vtk = LEGACY.replace("3 0 2 3", "3 0 2 4");
    expect_io(
        &put(&d, "o.vtk", vtk.as_bytes()),
        &["face 1 refers to vertex 4"],
    );
    let vtp = r#"<VTKFile type="PolyData"><PolyData><Piece NumberOfPoints="3" NumberOfPolys="1">
<Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 0 1 0</DataArray></Points>
<Polys><DataArray type="Int32" Name="connectivity" format="ascii">0 1 3</DataArray>
<DataArray type="Int32" Name="offsets" format="ascii">3</DataArray></Polys></Piece></PolyData></VTKFile>"#;
    expect_io(
        &put(&d, "o.vtp", vtp.as_bytes()),
        &["face 0 refers to vertex 3"],
    );
}

#[test]
fn wrong_counts_are_reported() {
    let d = scratch("counts");
    // PLY: header promises 4 vertices, 3 present (then the face line is read as a vertex).
    let ply = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
        property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
        0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    expect_io(&put(&d, "c.ply", ply.as_bytes()), &["c.ply"]);
    // PLY: an element without properties declaring 10^16 items (its items take no bytes, so
    // reading them would loop that often): refused at once, the element named.
    let empty = "ply\nformat binary_little_endian 1.0\nelement v 10000000000000000\n\
        element vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
    let mut bytes = empty.as_bytes().to_vec();
    bytes.extend([0u8; 12]);
    expect_io(
        &put(&d, "e.ply", &bytes),
        &[
            "e.ply",
            "element `v` declares 10000000000000000 items but no properties",
        ],
    );
    // VTP: 4 points announced, 3 given.
    let vtp = r#"<VTKFile type="PolyData"><PolyData><Piece NumberOfPoints="4" NumberOfPolys="0">
<Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 0 1 0</DataArray></Points>
</Piece></PolyData></VTKFile>"#;
    expect_io(
        &put(&d, "c.vtp", vtp.as_bytes()),
        &["9 ascii values, expected 12"],
    );
    // VTP: offsets run past the connectivity.
    let vtp = r#"<VTKFile type="PolyData"><PolyData><Piece NumberOfPoints="3" NumberOfPolys="1">
<Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 0 1 0</DataArray></Points>
<Polys><DataArray type="Int32" Name="connectivity" format="ascii">0 1 2</DataArray>
<DataArray type="Int32" Name="offsets" format="ascii">4</DataArray></Polys></Piece></PolyData></VTKFile>"#;
    expect_io(
        &put(&d, "c2.vtp", vtp.as_bytes()),
        &["connectivity", "expected 4"],
    );
    // Legacy: size field disagrees with the cells.
    let vtk = LEGACY.replace("POLYGONS 2 8", "POLYGONS 2 9");
    expect_io(&put(&d, "c.vtk", vtk.as_bytes()), &["line"]);
    let vtk = LEGACY.replace("POLYGONS 2 8", "POLYGONS 3 8");
    expect_io(
        &put(&d, "c2.vtk", vtk.as_bytes()),
        &["POLYGONS: cell 2 claims"],
    );
    // Legacy: label count differs from the cells.
    let vtk = LEGACY
        .replace("CELL_DATA 2", "CELL_DATA 1")
        .replace("11 12\n", "11\n");
    expect_io(
        &put(&d, "c3.vtk", vtk.as_bytes()),
        &["CELL_DATA has 1 values for 2 cells"],
    );
    // Binary STL whose triangle count disagrees with the size.
    let mut stl = vec![0u8; 84 + 50];
    stl[80] = 2;
    expect_io(
        &put(&d, "c.stl", &stl),
        &["header says 2 triangles", "134 bytes"],
    );
    // Non-integer labels, non-finite coordinates, unsupported VTK types.
    let ply2 = ply
        .replace("element vertex 4", "element vertex 3")
        .replace(
            "property float z\n",
            "property float z\nproperty float label\n",
        )
        .replace("0 0 0\n1 0 0\n0 1 0\n", "0 0 0 11\n1 0 0 11.5\n0 1 0 11\n");
    expect_io(
        &put(&d, "l.ply", ply2.as_bytes()),
        &["vertex 1 has label 11.5"],
    );
    expect_io(
        &put(&d, "nan.obj", b"v 0 nan 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
        &["vertex 0", "non-finite"],
    );
    let ug = r#"<VTKFile type="UnstructuredGrid"><UnstructuredGrid/></VTKFile>"#;
    expect_io(
        &put(&d, "u.vtp", ug.as_bytes()),
        &["UnstructuredGrid", "PolyData"],
    );
    let sp = LEGACY.replace("DATASET POLYDATA", "DATASET STRUCTURED_POINTS");
    expect_io(&put(&d, "s.vtk", sp.as_bytes()), &["STRUCTURED_POINTS"]);
    expect_io(
        &put(&d, "f.obj", b"v 0 0 0\nv 1 x 0\n"),
        &["line 2", "\"x\" is not a number"],
    );
    expect_io(
        &put(&d, "z.obj", b"v 0 0 0\nf 0 1 1\n"),
        &["line 2", "index 0"],
    );
    expect_io(
        &put(&d, "two.obj", b"v 0 0 0\nv 1 0 0\nf 1 2\n"),
        &["face 0 has 2 vertices"],
    );
    assert!(
        read_mesh(d.join("missing.ply"))
            .unwrap_err()
            .to_string()
            .contains("cannot read")
    );
}
