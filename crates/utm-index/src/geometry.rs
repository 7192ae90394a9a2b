//! Exact horizontal distance between volume outlines (polygons and circles) in a local plane.
//!
//! Coordinates are metres east (x) and north (y) in one tangent plane. Outlines are closed
//! sets: two outlines that touch are at distance 0 (they intersect). Polygons may be convex or
//! not; they must be simple (no self-intersection), which the caller checks.
//!
//! Polygon–polygon: 0 if an edge of one crosses or touches an edge of the other, or one
//! contains a vertex of the other (even–odd rule); otherwise the smallest vertex–edge distance
//! (for disjoint segments the closest points include an endpoint). O(n·m) for n and m
//! vertices. Circle–polygon: max(0, d(centre, polygon) − r). Circle–circle: max(0, |c₁c₂| − r₁ − r₂).

/// A point (x east, y north), m.
pub type Pt = [f64; 2];

/// An outline borrowed from a [`crate::Volumes`] set.
#[derive(Clone, Copy, Debug)]
pub enum Outline<'a> {
    /// Polygon vertices (x, y), m, in order, not repeating the first.
    Polygon(&'a [Pt]),
    /// Circle: centre (x, y) and radius, m.
    Circle(Pt, f64),
}

fn sub(a: Pt, b: Pt) -> Pt {
    [a[0] - b[0], a[1] - b[1]]
}

fn cross(a: Pt, b: Pt) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

fn dot(a: Pt, b: Pt) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

/// Squared distance from `p` to the segment `a`–`b`, m².
pub fn point_segment_dist2(p: Pt, a: Pt, b: Pt) -> f64 {
    let ab = sub(b, a);
    let ap = sub(p, a);
    let len2 = dot(ab, ab);
    let t = if len2 > 0.0 {
        (dot(ap, ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let d = [ap[0] - t * ab[0], ap[1] - t * ab[1]];
    dot(d, d)
}

/// Whether the segments `a`–`b` and `c`–`d` cross at an interior point of both (proper
/// crossing); touching configurations are caught by the endpoint distances.
fn segments_cross(a: Pt, b: Pt, c: Pt, d: Pt) -> bool {
    let d1 = cross(sub(b, a), sub(c, a));
    let d2 = cross(sub(b, a), sub(d, a));
    let d3 = cross(sub(d, c), sub(a, c));
    let d4 = cross(sub(d, c), sub(b, c));
    ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
}

/// Whether `p` lies inside `poly` (even–odd rule; boundary points may go either way, the
/// distance test catches them).
pub fn point_in_polygon(p: Pt, poly: &[Pt]) -> bool {
    let mut inside = false;
    let n = poly.len();
    let mut j = n.wrapping_sub(1);
    for (i, &vi) in poly.iter().enumerate() {
        if let Some(&vj) = poly.get(j) {
            if (vi[1] > p[1]) != (vj[1] > p[1]) {
                let x = vj[0] + (p[1] - vj[1]) * (vi[0] - vj[0]) / (vi[1] - vj[1]);
                if p[0] < x {
                    inside = !inside;
                }
            }
        }
        j = i;
    }
    inside
}

fn edges(poly: &[Pt]) -> impl Iterator<Item = (Pt, Pt)> + '_ {
    poly.iter()
        .zip(poly.iter().cycle().skip(1))
        .map(|(&a, &b)| (a, b))
}

/// Distance from `p` to the polygon (0 inside or on the boundary), m.
pub fn point_polygon_dist(p: Pt, poly: &[Pt]) -> f64 {
    if point_in_polygon(p, poly) {
        return 0.0;
    }
    edges(poly)
        .map(|(a, b)| point_segment_dist2(p, a, b))
        .fold(f64::INFINITY, f64::min)
        .sqrt()
}

/// Distance between two polygons (0 if they intersect), m.
pub fn polygon_polygon_dist(a: &[Pt], b: &[Pt]) -> f64 {
    let mut best = f64::INFINITY;
    for (a0, a1) in edges(a) {
        for (b0, b1) in edges(b) {
            if segments_cross(a0, a1, b0, b1) {
                return 0.0;
            }
            let d = point_segment_dist2(a0, b0, b1)
                .min(point_segment_dist2(a1, b0, b1))
                .min(point_segment_dist2(b0, a0, a1))
                .min(point_segment_dist2(b1, a0, a1));
            best = best.min(d);
        }
    }
    if best == 0.0 {
        return 0.0;
    }
    if let (Some(&pa), Some(&pb)) = (a.first(), b.first()) {
        if point_in_polygon(pa, b) || point_in_polygon(pb, a) {
            return 0.0;
        }
    }
    best.sqrt()
}

/// Horizontal distance between two outlines (0 if they intersect), m.
pub fn outline_dist(a: Outline<'_>, b: Outline<'_>) -> f64 {
    match (a, b) {
        (Outline::Polygon(p), Outline::Polygon(q)) => polygon_polygon_dist(p, q),
        (Outline::Circle(c, r), Outline::Polygon(p))
        | (Outline::Polygon(p), Outline::Circle(c, r)) => (point_polygon_dist(c, p) - r).max(0.0),
        (Outline::Circle(c1, r1), Outline::Circle(c2, r2)) => {
            let d = sub(c1, c2);
            (dot(d, d).sqrt() - r1 - r2).max(0.0)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SQ: [Pt; 4] = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]];

    #[test]
    fn distances_by_hand() {
        let far: [Pt; 3] = [[13.0, 14.0], [20.0, 14.0], [20.0, 20.0]];
        // closest points (10, 10) and (13, 14): a 3-4-5 triangle
        assert!((polygon_polygon_dist(&SQ, &far) - 5.0).abs() < 1e-12);
        let inner: [Pt; 3] = [[2.0, 2.0], [3.0, 2.0], [2.0, 3.0]];
        assert_eq!(polygon_polygon_dist(&SQ, &inner), 0.0); // contained
        let touching: [Pt; 3] = [[10.0, 5.0], [15.0, 5.0], [15.0, 8.0]];
        assert_eq!(polygon_polygon_dist(&SQ, &touching), 0.0);
        assert!(
            (outline_dist(Outline::Circle([15.0, 5.0], 2.0), Outline::Polygon(&SQ)) - 3.0).abs()
                < 1e-12
        );
        assert_eq!(
            outline_dist(Outline::Circle([5.0, 5.0], 1.0), Outline::Polygon(&SQ)),
            0.0
        );
        assert!(
            (outline_dist(
                Outline::Circle([0.0, 0.0], 1.0),
                Outline::Circle([3.0, 4.0], 1.0)
            ) - 3.0)
                .abs()
                < 1e-12
        );
    }

    #[test]
    fn crossing_without_contained_vertices() {
        // a plus sign: two thin rectangles crossing, no vertex of either inside the other
        let h: [Pt; 4] = [[-10.0, -1.0], [10.0, -1.0], [10.0, 1.0], [-10.0, 1.0]];
        let v: [Pt; 4] = [[-1.0, -10.0], [1.0, -10.0], [1.0, 10.0], [-1.0, 10.0]];
        assert_eq!(polygon_polygon_dist(&h, &v), 0.0);
    }

    #[test]
    fn concave_polygon_pocket() {
        // a U shape; a square in the pocket does not touch it
        let u: [Pt; 8] = [
            [0.0, 0.0],
            [10.0, 0.0],
            [10.0, 10.0],
            [7.0, 10.0],
            [7.0, 3.0],
            [3.0, 3.0],
            [3.0, 10.0],
            [0.0, 10.0],
        ];
        let pocket: [Pt; 4] = [[4.0, 5.0], [6.0, 5.0], [6.0, 7.0], [4.0, 7.0]];
        assert!((polygon_polygon_dist(&u, &pocket) - 1.0).abs() < 1e-12);
    }
}
