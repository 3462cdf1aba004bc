//! Reading vertex positions from caller buffers: f32 or f64, any byte stride, any alignment.

use super::TriMesh;
use crate::{Error, Result};
use glam::DVec3;

/// Scalar type of a caller's vertex buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scalar {
    /// 32-bit IEEE float (converted exactly to f64).
    F32,
    /// 64-bit IEEE float (kept bit for bit).
    F64,
}

impl Scalar {
    /// Size in bytes of one scalar.
    pub fn size(self) -> usize {
        match self {
            Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
}

/// A borrowed, strided vertex buffer: `count` vertices, vertex `i`'s x/y/z at byte offset
/// `i * stride` of `bytes`, packed scalars of type `scalar`.
#[derive(Clone, Copy, Debug)]
pub struct VertexBuffer<'a> {
    /// The raw bytes (native endianness).
    pub bytes: &'a [u8],
    /// Number of vertices.
    pub count: usize,
    /// Bytes from one vertex to the next; at least `3 * scalar.size()`.
    pub stride: usize,
    /// Scalar type.
    pub scalar: Scalar,
}

impl<'a> VertexBuffer<'a> {
    /// Bytes the buffer must hold for `count` vertices at `stride` (None on overflow).
    pub fn required_len(count: usize, stride: usize, scalar: Scalar) -> Option<usize> {
        if count == 0 {
            return Some(0);
        }
        (count - 1)
            .checked_mul(stride)?
            .checked_add(3 * scalar.size())
    }

    /// Checks stride and length; the message says what is wrong.
    pub fn check(&self) -> Result<()> {
        let min = 3 * self.scalar.size();
        if self.stride < min {
            return Err(Error::InvalidArgument(format!(
                "vertex stride {} bytes is smaller than one vertex ({} bytes for 3 {:?} values)",
                self.stride, min, self.scalar
            )));
        }
        let need = Self::required_len(self.count, self.stride, self.scalar).ok_or_else(|| {
            Error::InvalidArgument(format!(
                "{} vertices at stride {} overflow the address space",
                self.count, self.stride
            ))
        })?;
        if self.bytes.len() < need {
            return Err(Error::InvalidArgument(format!(
                "vertex buffer holds {} bytes but {} vertices at stride {} need {}",
                self.bytes.len(),
                self.count,
                self.stride,
                need
            )));
        }
        Ok(())
    }

    /// Reads all positions as f64 (exact for f32). Fails on a bad stride/length or a
    /// non-finite coordinate (naming the vertex).
    pub fn read(&self) -> Result<Vec<DVec3>> {
        self.check()?;
        let s = self.scalar.size();
        let mut out = Vec::with_capacity(self.count);
        for i in 0..self.count {
            let base = i * self.stride;
            let mut c = [0.0f64; 3];
            for (k, ck) in c.iter_mut().enumerate() {
                let o = base + k * s;
                *ck = match self.scalar {
                    Scalar::F32 => {
                        f32::from_ne_bytes(self.bytes[o..o + 4].try_into().expect("4 bytes")) as f64
                    }
                    Scalar::F64 => {
                        f64::from_ne_bytes(self.bytes[o..o + 8].try_into().expect("8 bytes"))
                    }
                };
            }
            let p = DVec3::from_array(c);
            if !p.is_finite() {
                return Err(Error::NonFinite { vertex: i });
            }
            out.push(p);
        }
        Ok(out)
    }
}

impl TriMesh {
    /// Builds a mesh from a caller's vertex buffer and flat `u32` triangle indices
    /// (`indices.len()` must be a multiple of 3). Checks finiteness and index range only; see
    /// [`TriMesh::validate`] for topology.
    pub fn from_buffers(vertices: VertexBuffer<'_>, indices: &[u32]) -> Result<TriMesh> {
        if !indices.len().is_multiple_of(3) {
            return Err(Error::InvalidArgument(format!(
                "index count {} is not a multiple of 3",
                indices.len()
            )));
        }
        let positions = vertices.read()?;
        let n = positions.len();
        let mut triangles = Vec::with_capacity(indices.len() / 3);
        for (f, t) in indices.chunks_exact(3).enumerate() {
            for &v in t {
                if v as usize >= n {
                    return Err(Error::IndexOutOfBounds {
                        face: f,
                        index: v,
                        vertex_count: n,
                    });
                }
            }
            triangles.push([t[0], t[1], t[2]]);
        }
        Ok(TriMesh::new(positions, triangles))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bytes_f32(v: &[f32]) -> Vec<u8> {
        v.iter().flat_map(|x| x.to_ne_bytes()).collect()
    }

    #[test]
    fn strided_f32_reads_exactly() {
        // 4 floats per vertex (x, y, z, pad), stride 16.
        let data = [0.1f32, 0.2, 0.3, 9.0, 1.5, -2.5, 1e-7, 9.0];
        let b = bytes_f32(&data);
        let vb = VertexBuffer {
            bytes: &b,
            count: 2,
            stride: 16,
            scalar: Scalar::F32,
        };
        let p = vb.read().unwrap();
        assert_eq!(p[0].x, 0.1f32 as f64);
        assert_eq!(p[1].z, 1e-7f32 as f64);
    }

    #[test]
    fn rejects_bad_stride_short_buffer_nan_and_bad_index() {
        let b = bytes_f32(&[0.0, 0.0, 0.0, 1.0, f32::NAN, 0.0]);
        let short = VertexBuffer {
            bytes: &b,
            count: 3,
            stride: 12,
            scalar: Scalar::F32,
        };
        assert!(matches!(short.check(), Err(Error::InvalidArgument(_))));
        let narrow = VertexBuffer {
            bytes: &b,
            count: 1,
            stride: 8,
            scalar: Scalar::F32,
        };
        assert!(matches!(narrow.check(), Err(Error::InvalidArgument(_))));
        let nan = VertexBuffer {
            bytes: &b,
            count: 2,
            stride: 12,
            scalar: Scalar::F32,
        };
        assert_eq!(nan.read(), Err(Error::NonFinite { vertex: 1 }));
        let ok = VertexBuffer {
            bytes: &b[..12],
            count: 1,
            stride: 12,
            scalar: Scalar::F32,
        };
        assert_eq!(
            TriMesh::from_buffers(ok, &[0, 0, 1]),
            Err(Error::IndexOutOfBounds {
                face: 0,
                index: 1,
                vertex_count: 1
            })
        );
    }
}
