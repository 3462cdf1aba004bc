//! Binary payloads of VTK XML arrays: base64 (possibly several padded chunks), the UInt32 /
//! UInt64 size header, `vtkZLibDataCompressor` blocks, and typed numbers in either byte order.

use base64::Engine;
use std::io::Read;

/// How a file's binary blocks are laid out (from the `VTKFile` attributes).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct BlockFormat {
    /// `byte_order="BigEndian"`.
    pub big_endian: bool,
    /// `header_type="UInt64"`.
    pub header64: bool,
    /// `compressor="vtkZLibDataCompressor"`.
    pub compressed: bool,
}

/// Size in bytes of a VTK XML scalar type.
pub(super) fn type_size(ty: &str) -> Option<usize> {
    Some(match ty {
        "Int8" | "UInt8" | "Char" => 1,
        "Int16" | "UInt16" => 2,
        "Int32" | "UInt32" | "Float32" => 4,
        "Int64" | "UInt64" | "Float64" => 8,
        _ => return None,
    })
}

/// Reads one binary block (header + data, optionally zlib-compressed in blocks) that must
/// decode to exactly `want` bytes; trailing bytes after it are ignored.
pub(super) fn block(
    fmt: BlockFormat,
    b: &[u8],
    want: usize,
) -> std::result::Result<Vec<u8>, String> {
    let hs = if fmt.header64 { 8 } else { 4 };
    let word = |i: usize| -> std::result::Result<u64, String> {
        let s = b
            .get(i * hs..(i + 1) * hs)
            .ok_or_else(|| format!("header truncated ({} bytes, word {i} needed)", b.len()))?;
        let mut v = [0u8; 8];
        if fmt.big_endian {
            v[8 - hs..].copy_from_slice(s);
            Ok(u64::from_be_bytes(v))
        } else {
            v[..hs].copy_from_slice(s);
            Ok(u64::from_le_bytes(v))
        }
    };
    if !fmt.compressed {
        let n = word(0)?;
        if n != want as u64 {
            return Err(format!("header says {n} bytes, expected {want}"));
        }
        return b.get(hs..hs + want).map(<[u8]>::to_vec).ok_or_else(|| {
            format!(
                "data truncated: {} of {want} bytes present",
                b.len().saturating_sub(hs)
            )
        });
    }
    let nb = word(0)?;
    let bs = word(1)?;
    let last = word(2)?;
    let total = match nb {
        0 => 0,
        n => (n - 1)
            .saturating_mul(bs)
            .saturating_add(if last > 0 { last } else { bs }),
    };
    if total != want as u64 {
        return Err(format!(
            "compressed header says {nb} blocks of {bs} bytes (last {last}) = {total} bytes, expected {want}"
        ));
    }
    if nb > 0 && bs == 0 {
        return Err(format!("compressed header has {nb} blocks of size 0"));
    }
    let nb = nb as usize; // bounded: total == want and bs > 0, so nb <= want / bs + 1
    let mut pos = (3 + nb) * hs;
    // Sized by what the compressed bytes can inflate to (zlib expands at most ~1032:1), not by
    // the header alone: a header may declare gigabytes that the data does not hold.
    let mut out = Vec::with_capacity(want.min(b.len().saturating_mul(1032)));
    for i in 0..nb {
        let cs = word(3 + i)? as usize;
        let src = b
            .get(pos..pos.saturating_add(cs))
            .ok_or_else(|| format!("compressed block {i} truncated"))?;
        let expect = if i + 1 == nb && last > 0 { last } else { bs } as usize;
        let before = out.len();
        flate2::read::ZlibDecoder::new(src)
            .take(expect as u64)
            .read_to_end(&mut out)
            .map_err(|e| format!("zlib block {i}: {e}"))?;
        if out.len() - before != expect {
            return Err(format!(
                "zlib block {i} inflates to {} bytes, expected {expect}",
                out.len() - before
            ));
        }
        pos += cs;
    }
    Ok(out)
}

/// Decodes base64 that may be several separately padded chunks back to back (VTK encodes the
/// compression header and the data separately); whitespace is ignored.
pub(super) fn b64(text: &[u8]) -> std::result::Result<Vec<u8>, String> {
    let clean: Vec<u8> = text
        .iter()
        .copied()
        .filter(|c| !c.is_ascii_whitespace())
        .collect();
    if !clean.len().is_multiple_of(4) {
        return Err(format!(
            "base64 text of {} characters is not a multiple of 4",
            clean.len()
        ));
    }
    let eng = base64::engine::general_purpose::STANDARD;
    let mut out = Vec::with_capacity(clean.len() / 4 * 3);
    let mut start = 0;
    for g in (0..clean.len()).step_by(4) {
        if clean[g..g + 4].contains(&b'=') || g + 4 == clean.len() {
            eng.decode_vec(&clean[start..g + 4], &mut out)
                .map_err(|e| format!("bad base64: {e}"))?;
            start = g + 4;
        }
    }
    Ok(out)
}

pub(super) fn to_f64(raw: &[u8], ty: &str, size: usize, big: bool) -> Vec<f64> {
    raw.chunks_exact(size)
        .map(|c| {
            let mut b = [0u8; 8];
            b[..size].copy_from_slice(c);
            if big {
                b[..size].reverse();
            }
            // `b` now holds the value little-endian in its first `size` bytes.
            match ty {
                "Int8" | "Char" => b[0] as i8 as f64,
                "UInt8" => b[0] as f64,
                "Int16" => i16::from_le_bytes([b[0], b[1]]) as f64,
                "UInt16" => u16::from_le_bytes([b[0], b[1]]) as f64,
                "Int32" => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                "UInt32" => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                "Float32" => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                "Int64" => i64::from_le_bytes(b) as f64,
                "UInt64" => u64::from_le_bytes(b) as f64,
                _ => f64::from_le_bytes(b),
            }
        })
        .collect()
}
