//! A closed plane polygon (a band loop in the triangulation plane) indexed for the two queries
//! the triangulation asks of every band point: inside or not (even-odd rule) and distance.
//! Both answers are exactly those of a scan over every edge: the index only leaves out edges
//! that cannot change them (edges not spanning the query's height for the parity; edges in
//! cells farther than the nearest edge found for the distance).

/// A polygon with its edges binned in rows (for the parity) and in square cells (for the
/// distance).
pub(crate) struct Polygon<'a> {
    pts: &'a [[f64; 2]],
    lo: [f64; 2],
    cell: f64,
    nx: usize,
    ny: usize,
    /// Per row of cells: the edges whose height range meets the row.
    rows: Vec<Vec<u32>>,
    /// Per cell (row-major): the edges whose bounding box meets the cell.
    cells: Vec<Vec<u32>>,
}

impl<'a> Polygon<'a> {
    /// Indexes the closed polygon `pts` (edge `i` joins `pts[i]` and `pts[i + 1]`, wrapping).
    pub(crate) fn new(pts: &'a [[f64; 2]]) -> Polygon<'a> {
        let n = pts.len();
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in pts {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let (w, h) = ((hi[0] - lo[0]).max(0.0), (hi[1] - lo[1]).max(0.0));
        // About one edge per cell along the outline: ~sqrt(n) cells per side.
        let side = (n as f64).sqrt().ceil().max(1.0);
        let cell = (w.max(h) / side).max(f64::MIN_POSITIVE);
        let finite = lo[0].is_finite() && lo[1].is_finite() && cell.is_finite();
        let (nx, ny) = if finite {
            (
                ((w / cell).floor() as usize + 1).min(4096),
                ((h / cell).floor() as usize + 1).min(4096),
            )
        } else {
            (1, 1)
        };
        let mut poly = Polygon {
            pts,
            lo: if finite { lo } else { [0.0; 2] },
            cell: if finite { cell } else { 1.0 },
            nx,
            ny,
            rows: vec![Vec::new(); ny],
            cells: vec![Vec::new(); nx * ny],
        };
        for i in 0..n {
            let (a, b) = (pts[i], pts[(i + 1) % n]);
            let (x0, x1) = (poly.ix(a[0].min(b[0])), poly.ix(a[0].max(b[0])));
            let (y0, y1) = (poly.iy(a[1].min(b[1])), poly.iy(a[1].max(b[1])));
            for y in y0..=y1 {
                poly.rows[y].push(i as u32);
                for x in x0..=x1 {
                    poly.cells[y * nx + x].push(i as u32);
                }
            }
        }
        poly
    }

    fn ix(&self, x: f64) -> usize {
        (((x - self.lo[0]) / self.cell).floor().max(0.0) as usize).min(self.nx - 1)
    }

    fn iy(&self, y: f64) -> usize {
        (((y - self.lo[1]) / self.cell).floor().max(0.0) as usize).min(self.ny - 1)
    }

    fn edge(&self, i: u32) -> ([f64; 2], [f64; 2]) {
        let i = i as usize;
        (self.pts[i], self.pts[(i + 1) % self.pts.len()])
    }

    /// Whether `q` is inside (even-odd rule; points on the outline as the crossing rule says).
    pub(crate) fn contains(&self, q: [f64; 2]) -> bool {
        // Below, above or NaN: no edge spans the query's height.
        let row = ((q[1] - self.lo[1]) / self.cell).floor();
        if self.pts.is_empty() || q[1] < self.lo[1] || row.is_nan() || row >= self.ny as f64 {
            return false;
        }
        let mut inside = false;
        for &i in &self.rows[row as usize] {
            let (a, b) = self.edge(i);
            if (a[1] > q[1]) != (b[1] > q[1]) {
                let x = a[0] + (q[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
                if q[0] < x {
                    inside = !inside;
                }
            }
        }
        inside
    }

    /// Distance from `q` to the outline.
    pub(crate) fn distance(&self, q: [f64; 2]) -> f64 {
        let mut best = f64::INFINITY;
        if self.pts.is_empty() {
            return best;
        }
        let (cx, cy) = (self.ix(q[0]) as i64, self.iy(q[1]) as i64);
        let (nx, ny) = (self.nx as i64, self.ny as i64);
        for r in 0..nx.max(ny) {
            for y in (cy - r).max(0)..=(cy + r).min(ny - 1) {
                for x in (cx - r).max(0)..=(cx + r).min(nx - 1) {
                    // Only the ring at Chebyshev distance r.
                    if (x - cx).abs() != r && (y - cy).abs() != r {
                        continue;
                    }
                    for &i in &self.cells[(y * nx + x) as usize] {
                        let (a, b) = self.edge(i);
                        best = best.min(segment_distance(a, b, q));
                    }
                }
            }
            // Cells beyond ring r lie at least r cells from q (or from its projection onto the
            // grid, which is no farther from them than q is).
            if best <= r as f64 * self.cell {
                break;
            }
        }
        best
    }
}

/// Distance from `q` to segment `a`–`b`.
fn segment_distance(a: [f64; 2], b: [f64; 2], q: [f64; 2]) -> f64 {
    let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
    let l2 = ex * ex + ey * ey;
    let t = if l2 > 0.0 {
        (((q[0] - a[0]) * ex + (q[1] - a[1]) * ey) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (dx, dy) = (a[0] + t * ex - q[0], a[1] + t * ey - q[1]);
    (dx * dx + dy * dy).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scan_contains(poly: &[[f64; 2]], q: [f64; 2]) -> bool {
        let n = poly.len();
        let mut inside = false;
        for i in 0..n {
            let (a, b) = (poly[i], poly[(i + 1) % n]);
            if (a[1] > q[1]) != (b[1] > q[1]) {
                let x = a[0] + (q[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
                if q[0] < x {
                    inside = !inside;
                }
            }
        }
        inside
    }

    fn scan_distance(poly: &[[f64; 2]], q: [f64; 2]) -> f64 {
        let n = poly.len();
        (0..n)
            .map(|i| segment_distance(poly[i], poly[(i + 1) % n], q))
            .fold(f64::INFINITY, f64::min)
    }

    /// On a jagged star-shaped loop (uneven edges, deep notches) the indexed answers are
    /// bitwise those of a scan over every edge, for queries inside, outside, far away, on
    /// vertices and on the loop's own heights.
    #[test]
    fn indexed_answers_equal_the_scan() {
        let n = 700;
        let poly: Vec<[f64; 2]> = (0..n)
            .map(|i| {
                let a = std::f64::consts::TAU * (i as f64 + 0.3 * ((i * 7) % 5) as f64) / n as f64;
                let r = 3.0 + 0.8 * (a * 9.0).sin() + if i % 97 < 4 { -1.5 } else { 0.0 };
                [r * a.cos(), r * a.sin()]
            })
            .collect();
        let p = Polygon::new(&poly);
        let mut rng = crate::phantom::rng::Rng::new(9);
        let mut next = || rng.unit();
        let mut inside = 0;
        let mut queries: Vec<[f64; 2]> = (0..4000)
            .map(|_| [12.0 * next() - 6.0, 12.0 * next() - 6.0])
            .collect();
        queries.extend(poly.iter().step_by(13).copied());
        queries.extend(poly.iter().step_by(17).map(|v| [0.5 * v[0], v[1]]));
        queries.push([40.0, -25.0]);
        for q in queries {
            assert_eq!(p.contains(q), scan_contains(&poly, q), "{q:?}");
            assert_eq!(
                p.distance(q).to_bits(),
                scan_distance(&poly, q).to_bits(),
                "{q:?}"
            );
            inside += p.contains(q) as usize;
        }
        assert!(inside > 500, "{inside}");
    }
}
