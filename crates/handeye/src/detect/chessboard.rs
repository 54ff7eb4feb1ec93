//! A chessboard's inner corners in an image, by `calib-targets` (ChESS corners, a labelled grid,
//! sub-pixel positions), put in the board's own order.
//!
//! The detector labels its grid from the image's top-left; the board's frame must not depend on
//! the view. Its rows and columns are told apart by their counts, and which of the two corners
//! left by a half turn is (0, 0) by the squares' colours: the cell between corners (i, j) and
//! (i + 1, j + 1) is dark when i + j is even (OpenCV's and ViSP's corner order on ViSP's board, as
//! `tests/images.rs` checks image by image). A half turn changes that parity when `cols + rows`
//! is odd, which `Target` requires.

use calib_targets::chessboard::ChessboardParams;
use calib_targets::detect::{default_chess_config, detect_chessboard};
use image::GrayImage;

/// The board's inner corners (row by row, `cols` a row) in the image, or why not.
pub fn find(image: &GrayImage, cols: usize, rows: usize) -> Result<Vec<[f64; 2]>, String> {
    let found = detect_chessboard(image, &default_chess_config(), &ChessboardParams::default())
        .map_err(|e| format!("no chessboard found ({e})"))?;
    let (mut width, mut height) = (0usize, 0usize);
    for c in &found.corners {
        if c.grid.u < 0 || c.grid.v < 0 {
            return Err("the detector gave a negative grid label".into());
        }
        width = width.max(c.grid.u as usize + 1);
        height = height.max(c.grid.v as usize + 1);
    }
    let whole = found.corners.len() == cols * rows
        && ((width, height) == (cols, rows) || (width, height) == (rows, cols));
    if !whole {
        return Err(format!(
            "{} corners found in a {width}x{height} grid, the target has {cols}x{rows}: part of the board is hidden, out of the image, or the spec's size is not the board's",
            found.corners.len()
        ));
    }
    // grid[v][u], the detector's labels.
    let mut grid = vec![vec![None; width]; height];
    for c in &found.corners {
        let cell = &mut grid[c.grid.v as usize][c.grid.u as usize];
        if cell.is_some() {
            return Err("the detector labelled two corners alike".into());
        }
        *cell = Some([f64::from(c.position.x), f64::from(c.position.y)]);
    }
    let at = |u: usize, v: usize| grid[v][u].ok_or("the detector's grid has a hole");
    // (row i, column j) → the detector's (u, v): x along the rows when the grid is as wide as a
    // row, else turned a quarter (x down the image, y to the left), both right-handed in the image.
    let label = |i: usize, j: usize, turned: bool| -> (usize, usize) {
        let (u, v) = if width == cols {
            (j, i)
        } else {
            (width - 1 - i, j)
        };
        if turned {
            (width - 1 - u, height - 1 - v)
        } else {
            (u, v)
        }
    };
    let ordered = |turned: bool| -> Result<Vec<[f64; 2]>, String> {
        let mut out = Vec::with_capacity(cols * rows);
        for i in 0..rows {
            for j in 0..cols {
                let (u, v) = label(i, j, turned);
                out.push(at(u, v)?);
            }
        }
        Ok(out)
    };
    let corners = ordered(false)?;
    match even_cells_dark(image, &corners, cols, rows) {
        Some(true) => Ok(corners),
        Some(false) => ordered(true),
        None => Err("the squares' colours do not tell which corner is the board's first".into()),
    }
}

/// Whether the cells whose first corner (i, j) has i + j even are the darker ones (`None` when the
/// two kinds of cell are not told apart: the mean of each kind within 10 grey levels).
fn even_cells_dark(
    image: &GrayImage,
    corners: &[[f64; 2]],
    cols: usize,
    rows: usize,
) -> Option<bool> {
    let (mut sum, mut n) = ([0.0f64; 2], [0usize; 2]);
    for i in 0..rows - 1 {
        for j in 0..cols - 1 {
            let c = [
                corners[i * cols + j],
                corners[i * cols + j + 1],
                corners[(i + 1) * cols + j],
                corners[(i + 1) * cols + j + 1],
            ];
            let centre = [
                c.iter().map(|p| p[0]).sum::<f64>() / 4.0,
                c.iter().map(|p| p[1]).sum::<f64>() / 4.0,
            ];
            if let Some(grey) = grey_at(image, centre) {
                sum[(i + j) % 2] += grey;
                n[(i + j) % 2] += 1;
            }
        }
    }
    if n[0] == 0 || n[1] == 0 {
        return None;
    }
    let (even, odd) = (sum[0] / n[0] as f64, sum[1] / n[1] as f64);
    ((even - odd).abs() > 10.0).then_some(even < odd)
}

/// The mean grey of the 3×3 pixels around `p`, or `None` outside the image.
fn grey_at(image: &GrayImage, p: [f64; 2]) -> Option<f64> {
    let (u, v) = (p[0].round(), p[1].round());
    if !(u >= 1.0 && v >= 1.0) {
        return None;
    }
    let (u, v) = (u as u32, v as u32);
    if u + 1 >= image.width() || v + 1 >= image.height() {
        return None;
    }
    let mut total = 0.0;
    for dv in 0..3 {
        for du in 0..3 {
            total += f64::from(image.get_pixel(u + du - 1, v + dv - 1).0[0]);
        }
    }
    Some(total / 9.0)
}
