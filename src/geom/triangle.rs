//! Closest point on a triangle (shared by the registration correspondences and the mesh checks).

use glam::DVec3;

/// Closest point to `p` on triangle `abc` (Ericson, *Real-Time Collision Detection*, 5.1.5).
/// A degenerate (zero-area) triangle whose interior region is reached returns `a`.
pub fn closest_point_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return a + ab * v;
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return a + ac * w;
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return b + (c - b) * w;
    }
    let denom = va + vb + vc;
    if denom.abs() < f64::MIN_POSITIVE {
        return a;
    }
    let v = vb / denom;
    let w = vc / denom;
    a + ab * v + ac * w
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangle_regions() {
        let (a, b, c) = (DVec3::ZERO, DVec3::X, DVec3::Y);
        assert_eq!(
            closest_point_on_triangle(DVec3::new(-1.0, -1.0, 3.0), a, b, c),
            a
        );
        assert_eq!(
            closest_point_on_triangle(DVec3::new(0.5, -1.0, 0.0), a, b, c),
            DVec3::new(0.5, 0.0, 0.0)
        );
        assert!(
            (closest_point_on_triangle(DVec3::new(0.2, 0.2, 5.0), a, b, c)
                - DVec3::new(0.2, 0.2, 0.0))
            .length()
                < 1e-12
        );
        assert_eq!(
            closest_point_on_triangle(DVec3::new(1.0, 1.0, 0.0), a, b, c),
            DVec3::new(0.5, 0.5, 0.0)
        );
    }
}
