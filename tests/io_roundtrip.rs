//! Round trips and hand-written variants for PLY, STL and OBJ.

mod io_common;

use glam::DVec3;
use io_common::{grid, grid_f32, put, scratch};
use toothfuse::TriMesh;
use toothfuse::io::{PlyEncoding, read_mesh, write_mesh, write_mesh_with};

fn labels(n: usize) -> Vec<i32> {
    (0..n).map(|i| [0, 11, 21, 36, 48][i % 5]).collect()
}

#[test]
fn ply_round_trip_is_bitwise_in_every_encoding() {
    let d = scratch("ply_rt");
    let m = grid(30, 1);
    let lab = labels(m.vertex_count());
    let src: Vec<i32> = (0..m.vertex_count() as i32).map(|i| -i).collect();
    for enc in [
        PlyEncoding::BinaryLittleEndian,
        PlyEncoding::BinaryBigEndian,
        PlyEncoding::Ascii,
    ] {
        let p = d.join(format!("m_{enc:?}.PLY"));
        write_mesh_with(&p, &m, &[("label", &lab), ("source", &src)], enc).unwrap();
        let back = read_mesh(&p).unwrap();
        assert_eq!(back.mesh.triangles, m.triangles, "{enc:?}");
        for (a, b) in back.mesh.positions.iter().zip(&m.positions) {
            assert_eq!(
                a.to_array().map(f64::to_bits),
                b.to_array().map(f64::to_bits)
            );
        }
        assert_eq!(back.vertex_labels.as_deref(), Some(&lab[..]), "{enc:?}");
        assert!(back.face_labels.is_none());
    }
    // Default write_mesh is binary little-endian with doubles.
    let p = d.join("default.ply");
    write_mesh(&p, &m, &[("label", &lab)]).unwrap();
    let head = std::fs::read(&p).unwrap();
    let text = String::from_utf8_lossy(&head[..200]);
    assert!(text.contains("binary_little_endian") && text.contains("property double x"));
    assert!(text.contains("property int label"));
    // A property with the wrong length is refused.
    assert!(write_mesh(&p, &m, &[("label", &lab[1..])]).is_err());
}

#[test]
fn ply_file_is_streamed_bytewise_as_written_in_memory_and_checked_before_it_is_touched() {
    let d = scratch("ply_stream");
    // Over 4 MB of payload: written to the file in several chunks.
    let m = grid(300, 1);
    let lab = labels(m.vertex_count());
    for enc in [PlyEncoding::BinaryLittleEndian, PlyEncoding::Ascii] {
        let p = d.join(format!("big_{enc:?}.ply"));
        write_mesh_with(&p, &m, &[("label", &lab)], enc).unwrap();
        let mut mem = Vec::new();
        toothfuse::io::write_ply(&mut mem, &m, &[("label", &lab)], enc).unwrap();
        assert!(mem.len() > 4 << 20, "{enc:?}: {} bytes", mem.len());
        assert!(std::fs::read(&p).unwrap() == mem, "{enc:?}");
    }
    // A refused property (bad name, wrong length) or face index leaves an existing file as it was.
    let p = d.join("kept.ply");
    std::fs::write(&p, b"not to be lost").unwrap();
    assert!(write_mesh(&p, &m, &[("a label", &lab)]).is_err());
    assert!(write_mesh(&p, &m, &[("label", &lab[1..])]).is_err());
    let mut bad = m.clone();
    bad.triangles[7][1] = bad.vertex_count() as u32;
    assert!(write_mesh(&p, &bad, &[]).is_err());
    assert_eq!(std::fs::read(&p).unwrap(), b"not to be lost");
}

#[test]
fn ply_ascii_variants_quads_face_labels_float_labels() {
    let d = scratch("ply_ascii");
    let text = "ply\nformat ascii 1.0\ncomment quad + triangle, an edge element, a colour\nelement vertex 5\n\
        property float x\nproperty float y\nproperty float z\nproperty float label\n\
        element edge 1\nproperty int vertex1\nproperty int vertex2\n\
        element face 2\nproperty list uchar uint vertex_index\nproperty ushort label\n\
        property uchar red\nend_header\n\
        0 0 0 11\n1 0 0 11\n1 1 0 11\n0 1 0 21\n2 0 0.5 21\n0 1\n\
        4 0 1 2 3 36 255\n3 1 4 2 37 0\n";
    let lm = read_mesh(put(&d, "a.ply", text.as_bytes())).unwrap();
    assert_eq!(lm.mesh.vertex_count(), 5);
    assert_eq!(lm.mesh.triangles, vec![[0, 1, 2], [0, 2, 3], [1, 4, 2]]);
    assert_eq!(lm.vertex_labels, Some(vec![11, 11, 11, 21, 21]));
    assert_eq!(lm.face_labels, Some(vec![36, 36, 37]));
    assert_eq!(lm.mesh.positions[4], DVec3::new(2.0, 0.0, 0.5));
}

#[test]
fn ply_binary_big_endian_hand_written() {
    let d = scratch("ply_be");
    let mut b = b"ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\n\
        property double y\nproperty double z\nproperty short labels\nelement face 1\n\
        property list uchar short vertex_indices\nend_header\n"
        .to_vec();
    let pts = [[0.1, 0.2, 0.3], [1.5, -2.25, 1e-9], [3.0, 4.0, 5.0]];
    for (i, p) in pts.iter().enumerate() {
        for c in p {
            b.extend(f64::to_be_bytes(*c));
        }
        b.extend(((i as i16) * 10 + 11).to_be_bytes());
    }
    b.push(3);
    for v in [0i16, 2, 1] {
        b.extend(v.to_be_bytes());
    }
    let lm = read_mesh(put(&d, "b.ply", &b)).unwrap();
    assert_eq!(lm.mesh.positions[1], DVec3::new(1.5, -2.25, 1e-9));
    assert_eq!(lm.mesh.triangles, vec![[0, 2, 1]]);
    assert_eq!(lm.vertex_labels, Some(vec![11, 21, 31]));
}

#[test]
fn stl_binary_round_trip_welds_exactly() {
    let d = scratch("stl_rt");
    let m = grid_f32(25, 2);
    let p = d.join("g.stl");
    write_mesh(&p, &m, &[]).unwrap();
    let back = read_mesh(&p).unwrap();
    assert!(back.vertex_labels.is_none() && back.face_labels.is_none());
    // Welded back to the original vertex count; every triangle has the same corners, exactly.
    assert_eq!(back.mesh.vertex_count(), m.vertex_count());
    assert_eq!(back.mesh.face_count(), m.face_count());
    for f in 0..m.face_count() {
        assert_eq!(back.mesh.corners(f), m.corners(f));
    }
    // Vertex order = first occurrence: the first triangle's corners are vertices 0, 1, 2.
    assert_eq!(back.mesh.triangles[0], [0, 1, 2]);
    // Writing again gives identical bytes (deterministic).
    let p2 = d.join("g2.stl");
    write_mesh(&p2, &back.mesh, &[]).unwrap();
    assert_eq!(std::fs::read(&p).unwrap(), std::fs::read(&p2).unwrap());
}

#[test]
fn stl_ascii_and_solid_headed_binary() {
    let d = scratch("stl_ascii");
    let ascii = "solid two\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\n\
        endloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 1 0\nvertex -0 1 0\n\
        endloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex 0 1 0\nvertex 1 1 0\nvertex 0 2 0\n\
        endloop\nendfacet\nendsolid two\n";
    let lm = read_mesh(put(&d, "a.STL", ascii.as_bytes())).unwrap();
    // -0 and 0 weld: 5 distinct points.
    assert_eq!(lm.mesh.vertex_count(), 5);
    assert_eq!(lm.mesh.triangles, vec![[0, 1, 2], [0, 2, 3], [3, 2, 4]]);

    // A binary STL whose 80-byte header starts with "solid " is still binary.
    let m = grid_f32(4, 3);
    let mut bytes = Vec::new();
    toothfuse::io::write_stl(&mut bytes, &m).unwrap();
    bytes[..12].copy_from_slice(b"solid binary");
    let back = read_mesh(put(&d, "b.stl", &bytes)).unwrap();
    assert_eq!(back.mesh.vertex_count(), m.vertex_count());
    assert_eq!(back.mesh.face_count(), m.face_count());
}

#[test]
fn obj_round_trip_exact_with_teeth3ds_labels() {
    let d = scratch("obj_rt");
    let m = grid(20, 4);
    let p = d.join("scan_upper.obj");
    write_mesh(&p, &m, &[]).unwrap();
    let back = read_mesh(&p).unwrap();
    assert_eq!(back.mesh, m);
    assert!(back.vertex_labels.is_none());

    let lab = labels(m.vertex_count());
    let json =
        serde_json::json!({"id_patient": "X", "jaw": "upper", "labels": lab, "instances": []});
    put(&d, "scan_upper.json", json.to_string().as_bytes());
    let back = read_mesh(&p).unwrap();
    assert_eq!(back.vertex_labels.as_deref(), Some(&lab[..]));

    // Wrong label count and wrong jaw are errors naming the JSON file.
    let bad = serde_json::json!({"jaw": "upper", "labels": &lab[1..]});
    put(&d, "scan_upper.json", bad.to_string().as_bytes());
    let e = read_mesh(&p).unwrap_err().to_string();
    assert!(
        e.contains("scan_upper.json") && e.contains("labels for"),
        "{e}"
    );
    let bad = serde_json::json!({"jaw": "middle", "labels": lab});
    put(&d, "scan_upper.json", bad.to_string().as_bytes());
    assert!(read_mesh(&p).unwrap_err().to_string().contains("middle"));
}

#[test]
fn obj_face_syntaxes_polygons_and_negative_indices() {
    let d = scratch("obj_syntax");
    let text = "# comment\nmtllib x.mtl\no thing\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n\
        g a\nusemtl m\ns 1\nf 1/1/1 2/1/1 3/1/1 4/1/1\nv 2 0 0\nf -4//1 -1//1 -3//1\nf 1/1 3/1 4/1\n";
    let lm = read_mesh(put(&d, "p.obj", text.as_bytes())).unwrap();
    assert_eq!(lm.mesh.vertex_count(), 5);
    assert_eq!(
        lm.mesh.triangles,
        vec![[0, 1, 2], [0, 2, 3], [1, 4, 2], [0, 2, 3]]
    );
}

#[test]
fn write_mesh_refuses_bad_indices_and_unknown_extensions() {
    let d = scratch("write_bad");
    let m = TriMesh::new(vec![DVec3::ZERO; 3], vec![[0, 1, 3]]);
    for ext in ["ply", "stl", "obj", "vtp"] {
        let e = write_mesh(d.join(format!("x.{ext}")), &m, &[]).unwrap_err();
        assert!(
            e.to_string().contains("face 0 refers to vertex 3"),
            "{ext}: {e}"
        );
    }
    let ok = grid(3, 5);
    let e = write_mesh(d.join("x.xyz"), &ok, &[])
        .unwrap_err()
        .to_string();
    assert!(e.contains("unknown mesh file extension"), "{e}");
    assert!(write_mesh(d.join("x.vtk"), &ok, &[]).is_err());
}
