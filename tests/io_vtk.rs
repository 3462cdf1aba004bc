//! VTK XML PolyData in every encoding, and legacy VTK (ASCII and big-endian BINARY, classic
//! and 5.1 OFFSETS/CONNECTIVITY layouts).

mod io_common;

use base64::Engine;
use glam::DVec3;
use io_common::{grid, put, scratch};
use toothfuse::io::{VtpEncoding, read_mesh, write_vtp};
use toothfuse::mesh::LabeledMesh;

/// Without a requested name one label array is read, the best-ranked by name (see
/// `toothfuse::io::KNOWN_LABEL_NAMES`): either the point or the cell array, with its values
/// exactly.
fn one_label_array(lm: &LabeledMesh, vertex: &[i32], face: &[i32], what: &str) {
    match (&lm.vertex_labels, &lm.face_labels) {
        (Some(v), None) => assert_eq!(&v[..], vertex, "{what}"),
        (None, Some(f)) => assert_eq!(&f[..], face, "{what}"),
        other => panic!("{what}: expected one label array, got {other:?}"),
    }
}

#[test]
fn vtp_round_trip_every_encoding_bitwise() {
    let d = scratch("vtp_rt");
    // 40×40 = 1600 points: 38 KB of Float64 points, several 16 KiB compression blocks.
    let m = grid(40, 7);
    let pl: Vec<i32> = (0..m.vertex_count() as i32).map(|i| i % 17).collect();
    let cl: Vec<i32> = (0..m.face_count() as i32).map(|i| 11 + i % 7).collect();
    let mut encs = vec![VtpEncoding::Ascii];
    for compressed in [false, true] {
        for header64 in [false, true] {
            encs.push(VtpEncoding::Binary {
                compressed,
                header64,
            });
            encs.push(VtpEncoding::AppendedRaw {
                compressed,
                header64,
            });
            encs.push(VtpEncoding::AppendedBase64 {
                compressed,
                header64,
            });
        }
    }
    for enc in encs {
        let mut bytes = Vec::new();
        write_vtp(&mut bytes, &m, &[("Labels", &pl)], &[("Label", &cl)], enc).unwrap();
        let p = put(&d, "m.vtp", &bytes);
        let back = read_mesh(&p).unwrap();
        assert_eq!(back.mesh.triangles, m.triangles, "{enc:?}");
        for (a, b) in back.mesh.positions.iter().zip(&m.positions) {
            assert_eq!(
                a.to_array().map(f64::to_bits),
                b.to_array().map(f64::to_bits),
                "{enc:?}"
            );
        }
        one_label_array(&back, &pl, &cl, &format!("{enc:?}"));
    }
}

/// Hand-written ASCII VTP: Float32 points, Int32 connectivity, a quad (fan) and a strip,
/// one vertex cell before them (so cell labels are offset by one), UInt8 and Float32 labels.
#[test]
fn vtp_ascii_polys_strips_and_cell_numbering() {
    let d = scratch("vtp_ascii");
    let x = r#"<?xml version="1.0"?>
<VTKFile type="PolyData" version="0.1" byte_order="LittleEndian">
 <PolyData>
  <Piece NumberOfPoints="6" NumberOfVerts="1" NumberOfLines="0" NumberOfStrips="1" NumberOfPolys="1">
   <PointData Scalars="label">
    <DataArray type="UInt8" Name="label" format="ascii">11 11 11 11 21 21</DataArray>
    <DataArray type="Float32" Name="other" format="ascii">1 2 3 4 5 6</DataArray>
   </PointData>
   <CellData>
    <DataArray type="Float32" Name="Label" format="ascii">99 36 37</DataArray>
   </CellData>
   <Points>
    <DataArray type="Float32" NumberOfComponents="3" format="ascii">
      0 0 0  1 0 0  1 1 0  0 1 0  2 0 0  2 1 0.25
    </DataArray>
   </Points>
   <Verts>
    <DataArray type="Int32" Name="connectivity" format="ascii">5</DataArray>
    <DataArray type="Int32" Name="offsets" format="ascii">1</DataArray>
   </Verts>
   <Polys>
    <DataArray type="Int32" Name="connectivity" format="ascii">0 1 2 3</DataArray>
    <DataArray type="Int32" Name="offsets" format="ascii">4</DataArray>
   </Polys>
   <Strips>
    <DataArray type="UInt16" Name="connectivity" format="ascii">1 4 2 5</DataArray>
    <DataArray type="UInt16" Name="offsets" format="ascii">4</DataArray>
   </Strips>
  </Piece>
 </PolyData>
</VTKFile>
"#;
    let lm = read_mesh(put(&d, "a.VTP", x.as_bytes())).unwrap();
    assert_eq!(lm.mesh.positions[5], DVec3::new(2.0, 1.0, 0.25));
    assert_eq!(
        lm.mesh.triangles,
        vec![[0, 1, 2], [0, 2, 3], [1, 4, 2], [2, 4, 5]] // strip: odd triangles flipped
    );
    one_label_array(&lm, &[11, 11, 11, 11, 21, 21], &[36, 36, 37, 37], "labels");
}

/// Big-endian appended raw data with a UInt64 header, Int64 connectivity, Float64 points.
#[test]
fn vtp_big_endian_appended_raw() {
    let d = scratch("vtp_be");
    let pts = [0.5f64, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 1e-7];
    let conn = [0i64, 1, 2];
    let offs = [3i64];
    let mut blob = Vec::new();
    let mut offsets = Vec::new();
    let mut push = |data: Vec<u8>| {
        offsets.push(blob.len());
        blob.extend((data.len() as u64).to_be_bytes());
        blob.extend(data);
    };
    push(pts.iter().flat_map(|v| v.to_be_bytes()).collect());
    push(conn.iter().flat_map(|v| v.to_be_bytes()).collect());
    push(offs.iter().flat_map(|v| v.to_be_bytes()).collect());
    let head = format!(
        r#"<VTKFile type="PolyData" byte_order="BigEndian" header_type="UInt64"><PolyData>
<Piece NumberOfPoints="3" NumberOfPolys="1"><Points>
<DataArray type="Float64" NumberOfComponents="3" format="appended" offset="{}"/></Points>
<Polys><DataArray type="Int64" Name="connectivity" format="appended" offset="{}"/>
<DataArray type="Int64" Name="offsets" format="appended" offset="{}"/></Polys></Piece></PolyData>
<AppendedData encoding="raw">
_"#,
        offsets[0], offsets[1], offsets[2]
    );
    let mut bytes = head.into_bytes();
    bytes.extend(&blob);
    bytes.extend(b"\n</AppendedData></VTKFile>\n");
    let lm = read_mesh(put(&d, "be.vtp", &bytes)).unwrap();
    assert_eq!(lm.mesh.positions[2], DVec3::new(0.0, 1.0, 1e-7));
    assert_eq!(lm.mesh.positions[0].x, 0.5);
    assert_eq!(lm.mesh.triangles, vec![[0, 1, 2]]);
    assert!(lm.vertex_labels.is_none() && lm.face_labels.is_none());
}

/// Inline base64 with the header encoded together with uncompressed data (one chunk).
#[test]
fn vtp_inline_binary_single_chunk() {
    let d = scratch("vtp_b64");
    let b64 = |bytes: Vec<u8>| base64::engine::general_purpose::STANDARD.encode(bytes);
    let enc = |data: Vec<u8>| {
        let mut v = (data.len() as u32).to_le_bytes().to_vec();
        v.extend(data);
        b64(v)
    };
    let pts: Vec<u8> = [0f32, 0., 0., 1., 0., 0., 0., 1., 0.]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let x = format!(
        r#"<VTKFile type="PolyData" byte_order="LittleEndian"><PolyData><Piece NumberOfPoints="3" NumberOfPolys="1">
<Points><DataArray type="Float32" NumberOfComponents="3" format="binary">
{}
</DataArray></Points><CellData><DataArray type="Int16" Name="labels" format="binary">{}</DataArray></CellData>
<Polys><DataArray type="UInt32" Name="connectivity" format="binary">{}</DataArray>
<DataArray type="UInt32" Name="offsets" format="binary">{}</DataArray></Polys></Piece></PolyData></VTKFile>"#,
        enc(pts),
        enc(46i16.to_le_bytes().to_vec()),
        enc([2u32, 1, 0].iter().flat_map(|v| v.to_le_bytes()).collect()),
        enc(3u32.to_le_bytes().to_vec()),
    );
    let lm = read_mesh(put(&d, "i.vtp", x.as_bytes())).unwrap();
    assert_eq!(lm.mesh.triangles, vec![[2, 1, 0]]);
    assert_eq!(lm.face_labels, Some(vec![46]));
}

const LEGACY_ASCII: &str = "# vtk DataFile Version 3.0
test mesh
ASCII
DATASET POLYDATA
POINTS 6 float
0 0 0 1 0 0 1 1 0
0 1 0 2 0 0 2 1 0.25
VERTICES 1 2
1 5
POLYGONS 1 5
4 0 1 2 3
TRIANGLE_STRIPS 1 5
4 1 4 2 5
POINT_DATA 6
NORMALS n float
0 0 1 0 0 1 0 0 1 0 0 1 0 0 1 0 0 1
FIELD FieldData 2
temperature 1 6 double
1 2 3 4 5 6
Labels 1 6 int
11 11 11 11 21 21
CELL_DATA 3
SCALARS label int 1
LOOKUP_TABLE default
99 36 37
";

#[test]
fn legacy_ascii_classic() {
    let d = scratch("vtk_ascii");
    let lm = read_mesh(put(&d, "a.vtk", LEGACY_ASCII.as_bytes())).unwrap();
    assert_eq!(lm.mesh.positions[5], DVec3::new(2.0, 1.0, 0.25));
    assert_eq!(
        lm.mesh.triangles,
        vec![[0, 1, 2], [0, 2, 3], [1, 4, 2], [2, 4, 5]] // strip: odd triangles flipped
    );
    one_label_array(&lm, &[11, 11, 11, 11, 21, 21], &[36, 36, 37, 37], "labels");
}

#[test]
fn legacy_ascii_offsets_connectivity() {
    let d = scratch("vtk_51");
    let text = "# vtk DataFile Version 5.1
vtk output
ASCII
DATASET POLYDATA
POINTS 5 double
0 0 0 1 0 0 1 1 0 0 1 0 2 0 0.125
METADATA
INFORMATION 0

POLYGONS 3 7
OFFSETS vtktypeint64
0 4 7
CONNECTIVITY vtktypeint64
0 1 2 3 1 4 2
CELL_DATA 2
SCALARS Label float
LOOKUP_TABLE default
13 14
";
    let lm = read_mesh(put(&d, "b.vtk", text.as_bytes())).unwrap();
    assert_eq!(lm.mesh.triangles, vec![[0, 1, 2], [0, 2, 3], [1, 4, 2]]);
    assert_eq!(lm.face_labels, Some(vec![13, 13, 14]));
    assert_eq!(lm.mesh.positions[4].z, 0.125);
}

/// BINARY legacy files are big-endian: both cell layouts, SCALARS with and without
/// LOOKUP_TABLE, double points.
#[test]
fn legacy_binary_both_layouts() {
    let d = scratch("vtk_bin");
    let pts = [
        0.1f64, 0.2, 0.3, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, -5.5,
    ];
    for modern in [false, true] {
        let mut b = b"# vtk DataFile Version 3.0\nbin\nBINARY\nDATASET POLYDATA\nPOINTS 4 double\n"
            .to_vec();
        pts.iter().for_each(|v| b.extend(v.to_be_bytes()));
        if modern {
            b.extend(b"\nPOLYGONS 3 6\nOFFSETS vtktypeint64\n");
            [0i64, 3, 6].iter().for_each(|v| b.extend(v.to_be_bytes()));
            b.extend(b"\nCONNECTIVITY vtktypeint64\n");
            [0i64, 1, 2, 0, 2, 3]
                .iter()
                .for_each(|v| b.extend(v.to_be_bytes()));
        } else {
            b.extend(b"\nPOLYGONS 2 8\n");
            [3i32, 0, 1, 2, 3, 0, 2, 3]
                .iter()
                .for_each(|v| b.extend(v.to_be_bytes()));
        }
        b.extend(b"\nPOINT_DATA 4\nSCALARS label short\nLOOKUP_TABLE default\n");
        [11i16, 12, 13, 14]
            .iter()
            .for_each(|v| b.extend(v.to_be_bytes()));
        b.extend(b"\nCELL_DATA 2\nSCALARS labels unsigned_char 1\n");
        b.extend([41u8, 42]);
        b.push(b'\n');
        let lm = read_mesh(put(&d, "b.vtk", &b)).unwrap();
        assert_eq!(
            lm.mesh.positions[0],
            DVec3::new(0.1, 0.2, 0.3),
            "modern={modern}"
        );
        assert_eq!(lm.mesh.positions[3].z, -5.5);
        assert_eq!(lm.mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        one_label_array(
            &lm,
            &[11, 12, 13, 14],
            &[41, 42],
            &format!("modern={modern}"),
        );
    }
}

/// Two pieces are merged: the second piece's indices are shifted by the first's points.
#[test]
fn vtp_multiple_pieces_merge() {
    let d = scratch("vtp_pieces");
    let piece = |z: f64, l: i32| {
        format!(
            r#"<Piece NumberOfPoints="3" NumberOfPolys="1"><CellData><DataArray type="Int32" Name="Label" format="ascii">{l}</DataArray></CellData>
<Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">0 0 {z} 1 0 {z} 0 1 {z}</DataArray></Points>
<Polys><DataArray type="Int64" Name="connectivity" format="ascii">0 1 2</DataArray>
<DataArray type="Int64" Name="offsets" format="ascii">3</DataArray></Polys></Piece>"#
        )
    };
    let x = format!(
        r#"<VTKFile type="PolyData"><PolyData>{}{}</PolyData></VTKFile>"#,
        piece(0.0, 11),
        piece(2.5, 12)
    );
    let lm = read_mesh(put(&d, "p.vtp", x.as_bytes())).unwrap();
    assert_eq!(lm.mesh.vertex_count(), 6);
    assert_eq!(lm.mesh.triangles, vec![[0, 1, 2], [3, 4, 5]]);
    assert_eq!(lm.mesh.positions[3].z, 2.5);
    assert_eq!(lm.face_labels, Some(vec![11, 12]));
}
