//! A small deterministic software renderer (z-buffer, Lambert shading, orthographic camera) for
//! the README pictures: no GPU, no window system, same image bit for bit on every machine.

use anyhow::{Context, Result};
use glam::DVec3;
use std::path::Path;
use toothfuse::TriMesh;

/// An RGB colour, components 0..1.
pub type Rgb = [f64; 3];

/// One mesh to draw, with a colour per vertex.
pub struct Item<'a> {
    /// Geometry.
    pub mesh: &'a TriMesh,
    /// One colour per vertex (faces take the mean of their corners).
    pub colors: Vec<Rgb>,
}

impl<'a> Item<'a> {
    /// A mesh in one colour.
    pub fn uniform(mesh: &'a TriMesh, c: Rgb) -> Self {
        Self {
            mesh,
            colors: vec![c; mesh.positions.len()],
        }
    }
}

/// A view: direction the camera looks along, and the screen's up direction.
#[derive(Clone, Copy)]
pub struct View {
    /// Direction from the camera into the scene.
    pub look: DVec3,
    /// Approximate up direction on screen.
    pub up: DVec3,
}

/// An RGB image.
pub struct Image {
    /// Width in pixels.
    pub w: usize,
    /// Height in pixels.
    pub h: usize,
    /// Row-major pixels.
    pub px: Vec<Rgb>,
}

impl Image {
    /// Places images side by side with a thin white gap.
    pub fn hstack(parts: &[Image]) -> Image {
        let gap = 8;
        let h = parts.iter().map(|p| p.h).max().unwrap_or(0);
        let w = parts.iter().map(|p| p.w).sum::<usize>() + gap * parts.len().saturating_sub(1);
        let mut out = Image {
            w,
            h,
            px: vec![[1.0; 3]; w * h],
        };
        let mut x0 = 0;
        for p in parts {
            for y in 0..p.h {
                for x in 0..p.w {
                    out.px[y * w + x0 + x] = p.px[y * p.w + x];
                }
            }
            x0 += p.w + gap;
        }
        out
    }

    /// Writes an 8-bit RGB PNG.
    pub fn save_png(&self, path: &Path) -> Result<()> {
        let f =
            std::fs::File::create(path).with_context(|| format!("creating {}", path.display()))?;
        let mut enc = png::Encoder::new(std::io::BufWriter::new(f), self.w as u32, self.h as u32);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut wr = enc.write_header()?;
        let data: Vec<u8> = self
            .px
            .iter()
            .flat_map(|c| c.map(|v| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8))
            .collect();
        wr.write_image_data(&data)?;
        Ok(())
    }
}

/// Renders `items` seen along `view`, fitted to a `w`×`h` image, 2×2 supersampled.
pub fn render(items: &[Item<'_>], view: View, w: usize, h: usize) -> Image {
    let ss = 2;
    let (sw, sh) = (w * ss, h * ss);
    let fwd = view.look.normalize();
    let right = fwd.cross(view.up).normalize();
    let up = right.cross(fwd);
    let proj = |p: DVec3| DVec3::new(p.dot(right), p.dot(up), p.dot(fwd));
    let (mut lo, mut hi) = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
    for it in items {
        for &p in &it.mesh.positions {
            let q = proj(p);
            lo = lo.min(q);
            hi = hi.max(q);
        }
    }
    let ext = (hi - lo).max(DVec3::splat(1e-9));
    let scale = 0.92 * (sw as f64 / ext.x).min(sh as f64 / ext.y);
    let cx = 0.5 * (lo.x + hi.x);
    let cy = 0.5 * (lo.y + hi.y);
    let to_screen = |q: DVec3| {
        DVec3::new(
            sw as f64 * 0.5 + (q.x - cx) * scale,
            sh as f64 * 0.5 - (q.y - cy) * scale,
            q.z,
        )
    };
    let mut depth = vec![f64::INFINITY; sw * sh];
    let mut color = vec![[1.0f64; 3]; sw * sh];
    let light = (-fwd + 0.5 * up - 0.3 * right).normalize();
    for it in items {
        let m = it.mesh;
        for t in &m.triangles {
            let [a, b, c] = t.map(|v| m.positions[v as usize]);
            let n = (b - a).cross(c - a).normalize_or_zero();
            let lambert = n.dot(light).abs();
            let facing = n.dot(-fwd).abs();
            let shade = 0.25 + 0.6 * lambert + 0.15 * facing;
            let col = t
                .iter()
                .fold([0.0; 3], |acc, &v| {
                    let c = it.colors[v as usize];
                    [
                        acc[0] + c[0] / 3.0,
                        acc[1] + c[1] / 3.0,
                        acc[2] + c[2] / 3.0,
                    ]
                })
                .map(|x| x * shade);
            let [sa, sb, sc] = [a, b, c].map(|p| to_screen(proj(p)));
            raster(&mut depth, &mut color, sw, sh, sa, sb, sc, col);
        }
    }
    // Downsample.
    let mut px = vec![[0.0; 3]; w * h];
    for y in 0..h {
        for x in 0..w {
            let mut acc = [0.0; 3];
            for dy in 0..ss {
                for dx in 0..ss {
                    let c = color[(y * ss + dy) * sw + x * ss + dx];
                    for k in 0..3 {
                        acc[k] += c[k] / (ss * ss) as f64;
                    }
                }
            }
            px[y * w + x] = acc;
        }
    }
    Image { w, h, px }
}

#[allow(clippy::too_many_arguments)]
fn raster(
    depth: &mut [f64],
    color: &mut [Rgb],
    w: usize,
    h: usize,
    a: DVec3,
    b: DVec3,
    c: DVec3,
    col: Rgb,
) {
    let area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    if area.abs() < 1e-12 {
        return;
    }
    let x0 = a.x.min(b.x).min(c.x).floor().max(0.0) as usize;
    let x1 = (a.x.max(b.x).max(c.x).ceil() as usize).min(w.saturating_sub(1));
    let y0 = a.y.min(b.y).min(c.y).floor().max(0.0) as usize;
    let y1 = (a.y.max(b.y).max(c.y).ceil() as usize).min(h.saturating_sub(1));
    for y in y0..=y1 {
        for x in x0..=x1 {
            let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
            let w0 = ((b.x - px) * (c.y - py) - (b.y - py) * (c.x - px)) / area;
            let w1 = ((c.x - px) * (a.y - py) - (c.y - py) * (a.x - px)) / area;
            let w2 = 1.0 - w0 - w1;
            if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                continue;
            }
            let z = w0 * a.z + w1 * b.z + w2 * c.z;
            let i = y * w + x;
            if z < depth[i] {
                depth[i] = z;
                color[i] = col;
            }
        }
    }
}
