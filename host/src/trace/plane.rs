//! Points on the sheet: vector helpers and a grid of points for neighbour queries, shared by
//! the tracer's stages (linking, bands, probing).

use std::collections::HashMap;

pub(crate) fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

pub(crate) fn norm(a: [f64; 2]) -> f64 {
    a[0].hypot(a[1])
}

pub(crate) fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    norm(sub(a, b))
}

/// `d` scaled to unit length; `None` for a zero vector.
/// The farthest any of `pts` lies from the nearest of the dense points `truth`, mm (0 without
/// points): how far a written polyline strays from a known curve, in tests.
#[cfg(test)]
pub(crate) fn farthest_from<'a>(
    pts: impl IntoIterator<Item = &'a [f64; 2]>,
    truth: &[[f64; 2]],
) -> f64 {
    pts.into_iter()
        .map(|p| {
            truth
                .iter()
                .map(|q| dist(*p, *q))
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max)
}

pub(crate) fn unit(d: [f64; 2]) -> Option<[f64; 2]> {
    let n = norm(d);
    (n > 1e-12).then(|| [d[0] / n, d[1] / n])
}

/// A grid cell's points, each with its value.
type Cell<T> = Vec<([f64; 2], T)>;

/// Points with a value each, on a square grid of cell `cell_mm`, for "what lies within r of
/// here" queries.
pub(crate) struct Grid<T> {
    cell_mm: f64,
    cells: HashMap<(i64, i64), Cell<T>>,
}

impl<T> Grid<T> {
    pub fn new(cell_mm: f64) -> Self {
        Self {
            cell_mm,
            cells: HashMap::new(),
        }
    }

    fn key(&self, p: [f64; 2]) -> (i64, i64) {
        (
            (p[0] / self.cell_mm).floor() as i64,
            (p[1] / self.cell_mm).floor() as i64,
        )
    }

    pub fn insert(&mut self, p: [f64; 2], value: T) {
        let k = self.key(p);
        self.cells.entry(k).or_default().push((p, value));
    }

    /// Every point in the cells that the square of half side `r` about `c` touches: all
    /// points within `r` of `c`, and maybe a few more (callers filter by distance). Cells in
    /// order of x, then y; points in order of insertion within a cell.
    pub fn around(&self, c: [f64; 2], r: f64) -> impl Iterator<Item = &([f64; 2], T)> + '_ {
        let (x0, y0) = self.key([c[0] - r, c[1] - r]);
        let (x1, y1) = self.key([c[0] + r, c[1] + r]);
        (x0..=x1)
            .flat_map(move |x| (y0..=y1).map(move |y| (x, y)))
            .filter_map(|k| self.cells.get(&k))
            .flatten()
    }

    /// The points within `r` of `c` (inclusive).
    pub fn within(&self, c: [f64; 2], r: f64) -> impl Iterator<Item = &([f64; 2], T)> + '_ {
        self.around(c, r).filter(move |(p, _)| dist(*p, c) <= r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn within_finds_exactly_the_points_in_reach() {
        let mut g = Grid::new(1.0);
        let pts: Vec<[f64; 2]> = (0..400)
            .map(|i| {
                let t = i as f64 * 0.37;
                [7.0 * t.sin() - 0.5, 5.0 * (1.3 * t).cos() + 0.25]
            })
            .collect();
        for (i, p) in pts.iter().enumerate() {
            g.insert(*p, i);
        }
        for c in [[0.0, 0.0], [-3.3, 2.1], [6.9, -4.95]] {
            for r in [0.2, 1.0, 2.7] {
                let mut got: Vec<usize> = g.within(c, r).map(|(_, i)| *i).collect();
                got.sort_unstable();
                let want: Vec<usize> = (0..pts.len()).filter(|&i| dist(pts[i], c) <= r).collect();
                assert_eq!(got, want, "c {c:?} r {r}");
            }
        }
    }

    #[test]
    fn unit_of_zero_is_none() {
        assert_eq!(unit([0.0, 0.0]), None);
        let u = unit([3.0, -4.0]).expect("non-zero");
        assert!((u[0] - 0.6).abs() < 1e-15 && (u[1] + 0.8).abs() < 1e-15);
    }
}
