//! Units of work: a store's chunks (and their mirror images on a symmetric grid) as the
//! tasks of `--tile I/N` share them.

use super::chunk_rows;
use crate::spec::Grid;

/// Bands of whole chunks computed together: a chunk, or a chunk and its mirror image through
/// the map's centre (computed once and written twice, as a whole map mirrors its top half).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Unit {
    pub chunk: u32,
    pub mirror: Option<u32>,
}

/// The units of a map of `height` rows in chunks of `chunk_rows` (the last may be shorter);
/// with `mirrored`, chunk c pairs with chunk C - 1 - c (then `height` is a multiple of
/// `chunk_rows`, so the pairs are exact images). Task `i` of `n` takes units i, i + n, ...
pub fn units(height: u32, chunk_rows: u32, mirrored: bool) -> Vec<Unit> {
    let chunks = height.div_ceil(chunk_rows);
    if !mirrored {
        return (0..chunks)
            .map(|chunk| Unit {
                chunk,
                mirror: None,
            })
            .collect();
    }
    (0..chunks.div_ceil(2))
        .map(|chunk| {
            let other = chunks - 1 - chunk;
            Unit {
                chunk,
                mirror: (other != chunk).then_some(other),
            }
        })
        .collect()
}

/// Whether the map of `grid` pairs mirrored chunks (a point-symmetric grid integrated with
/// its symmetry, in whole pairs of chunks).
pub fn pairs_mirrored(grid: &Grid, use_symmetry: bool) -> bool {
    use_symmetry
        && grid.point_symmetric()
        && grid
            .height
            .is_multiple_of(chunk_rows(grid.width, grid.height))
}

/// The units of task `index` of `tasks`, in an order spread over the map (bit-reversed), so
/// that the first units done foretell the rest's cost for the progress estimate.
pub fn task_units(all: &[Unit], index: u32, tasks: u32) -> Vec<Unit> {
    let mine: Vec<Unit> = all
        .iter()
        .copied()
        .skip(index as usize)
        .step_by(tasks as usize)
        .collect();
    let bits = mine.len().next_power_of_two().trailing_zeros();
    if bits == 0 {
        return mine;
    }
    let mut order: Vec<usize> = (0..mine.len()).collect();
    order.sort_by_key(|&k| k.reverse_bits() >> (usize::BITS - bits));
    order.into_iter().map(|k| mine[k]).collect()
}
