//! The broad phase: a uniform grid of square cells over the arena, rebuilt by a counting sort
//! (no allocation once sized). Each robot is filed under the cell of its centre; any two
//! bodies whose centres are less than one cell apart are in neighbouring cells.

/// A uniform grid of robot indices by cell, in robot-index order within each cell.
#[derive(Debug, Clone)]
pub(crate) struct Grid {
    cell_m: f64,
    inv_cell: f64,
    nx: usize,
    ny: usize,
    /// After a build, the robots of cell `c` are `items[start[c + 1]..start[c + 2]]`.
    start: Vec<u32>,
    items: Vec<u32>,
    cell_of: Vec<u32>,
    /// Robot centres at the last build, metres.
    pub build_xy: Vec<[f64; 2]>,
}

impl Grid {
    /// A grid over `[0, w] × [0, h]` with cells of at least `min_cell_m`, sized for `n` robots:
    /// cells are enlarged to about one robot per cell and to at most `4n + 1024` cells.
    pub(crate) fn new(w: f64, h: f64, min_cell_m: f64, n: usize) -> Grid {
        let area = w * h;
        let mut cell_m = min_cell_m.max((area / n.max(1) as f64).sqrt());
        let max_cells = 4 * n + 1024;
        loop {
            let nx = (w / cell_m).ceil().max(1.0);
            let ny = (h / cell_m).ceil().max(1.0);
            if nx * ny <= max_cells as f64 {
                break;
            }
            cell_m *= 1.25;
        }
        let nx = ((w / cell_m).ceil() as usize).max(1);
        let ny = ((h / cell_m).ceil() as usize).max(1);
        Grid {
            cell_m,
            inv_cell: 1.0 / cell_m,
            nx,
            ny,
            start: vec![0; nx * ny + 2],
            items: vec![0; n],
            cell_of: vec![0; n],
            build_xy: vec![[0.0; 2]; n],
        }
    }

    /// Cell side, metres.
    pub(crate) fn cell_m(&self) -> f64 {
        self.cell_m
    }

    /// Column of an x coordinate, clamped to the grid.
    #[inline]
    pub(crate) fn col(&self, x: f64) -> usize {
        let c = (x * self.inv_cell).floor();
        if c <= 0.0 {
            0
        } else if c >= (self.nx - 1) as f64 {
            self.nx - 1
        } else {
            c as usize
        }
    }

    /// Row of a y coordinate, clamped to the grid.
    #[inline]
    pub(crate) fn row(&self, y: f64) -> usize {
        let r = (y * self.inv_cell).floor();
        if r <= 0.0 {
            0
        } else if r >= (self.ny - 1) as f64 {
            self.ny - 1
        } else {
            r as usize
        }
    }

    /// Number of columns.
    #[inline]
    pub(crate) fn nx(&self) -> usize {
        self.nx
    }

    /// Number of rows.
    #[inline]
    pub(crate) fn ny(&self) -> usize {
        self.ny
    }

    /// The robots filed under cell (col, row).
    #[inline]
    pub(crate) fn cell(&self, col: usize, row: usize) -> &[u32] {
        let c = row * self.nx + col;
        let a = self.start[c + 1] as usize;
        let b = self.start[c + 2] as usize;
        &self.items[a..b]
    }

    /// The cell (col, row) a robot was filed under at the last build.
    #[inline]
    pub(crate) fn cell_of(&self, robot: usize) -> (usize, usize) {
        let c = self.cell_of[robot] as usize;
        (c % self.nx, c / self.nx)
    }

    /// Files every robot by its centre (counting sort, stable in robot index).
    pub(crate) fn build(&mut self, xy: impl Iterator<Item = (f64, f64)>) {
        self.start.fill(0);
        let ncells = self.nx * self.ny;
        for (i, (x, y)) in xy.enumerate() {
            let c = self.row(y) * self.nx + self.col(x);
            self.cell_of[i] = c as u32;
            self.build_xy[i] = [x, y];
            self.start[c + 1] += 1;
        }
        // Inclusive prefix sums: start[c + 1] = end of cell c.
        let mut acc = 0u32;
        for s in &mut self.start[1..=ncells] {
            acc += *s;
            *s = acc;
        }
        self.start[ncells + 1] = acc;
        // Scatter from the back so each start[c + 1] ends at the beginning of cell c and the
        // robots of a cell stay in increasing index order.
        for i in (0..self.cell_of.len()).rev() {
            let c = self.cell_of[i] as usize;
            self.start[c + 1] -= 1;
            self.items[self.start[c + 1] as usize] = i as u32;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_robot_is_in_its_cell_once_in_order() {
        let pts: Vec<(f64, f64)> = (0..200)
            .map(|k| ((k * 37 % 101) as f64 * 0.05, (k * 53 % 97) as f64 * 0.05))
            .collect();
        let mut g = Grid::new(5.0, 5.0, 0.35, pts.len());
        g.build(pts.iter().copied());
        let mut seen = vec![0; pts.len()];
        for r in 0..g.ny() {
            for c in 0..g.nx() {
                let cell = g.cell(c, r);
                assert!(cell.windows(2).all(|w| w[0] < w[1]));
                for &i in cell {
                    seen[i as usize] += 1;
                    assert_eq!(g.cell_of(i as usize), (c, r));
                    let (x, y) = pts[i as usize];
                    assert_eq!((g.col(x), g.row(y)), (c, r));
                }
            }
        }
        assert!(seen.iter().all(|&s| s == 1));
    }

    #[test]
    fn cell_count_is_bounded() {
        let g = Grid::new(10_000.0, 10_000.0, 0.34, 3);
        assert!(g.nx() * g.ny() <= 4 * 3 + 1024);
        assert!(g.cell_m() >= 0.34);
    }
}
