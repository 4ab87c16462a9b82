//! The order in which a frame's modes (or `auto`'s candidates) take their
//! turns: balanced so that what runs just before one does not bias its
//! time.

/// The order in which `n` modes run in the frame numbered `order`: row
/// `order` of a Williams design, cycled, so that over every `n` frames (`2n`
/// for odd `n`) each mode runs in each place equally often and right after
/// each other mode equally often.
///
/// A mode's frame costs more or less by what ran just before it: the
/// reference before the first mode, or, on a software rasteriser, a mode
/// whose CPU work evicts the caches that the next mode's drawing needs
/// (measured on the teapot, lavapipe: `auto`'s `vfc` frames cost 4 % more
/// than `vfc`'s own when it ran after `swr` and `vfc` after `oracle`, and
/// 1.5 % less with the two swapped). A fixed cycle, merely rotated, keeps
/// every mode behind the same one all run long, a bias no number of
/// frames averages away; this order makes it noise.
pub fn balanced_order(order: usize, n: usize) -> impl Iterator<Item = usize> {
    let rows = if n.is_multiple_of(2) { n } else { 2 * n };
    let row = order % rows.max(1);
    // The first row runs 0, 1, n-1, 2, n-2, …; row r adds r, and for odd n
    // the second n rows are the first n reversed.
    let (shift, reversed) = (row % n.max(1), row >= n);
    (0..n).map(move |place| {
        let j = if reversed { n - 1 - place } else { place };
        let first_row = if j % 2 == 1 { j.div_ceil(2) } else { (n - j / 2) % n };
        (first_row + shift) % n
    })
}

#[cfg(test)]
mod tests {
    use super::balanced_order;

    /// Each mode runs in each place equally often, and right after each
    /// other mode equally often, over one cycle of orders.
    #[test]
    fn over_a_cycle_every_mode_runs_in_every_place_and_after_every_other_mode_equally_often() {
        for n in 1..=9usize {
            let rows = if n.is_multiple_of(2) { n } else { 2 * n };
            let mut places = vec![vec![0; n]; n];
            let mut after = vec![vec![0; n]; n];
            for order in 0..rows {
                let row: Vec<usize> = balanced_order(order, n).collect();
                let mut sorted = row.clone();
                sorted.sort_unstable();
                assert_eq!(sorted, (0..n).collect::<Vec<_>>(), "n = {n}, order {order}: {row:?}");
                for (place, &mode) in row.iter().enumerate() {
                    places[mode][place] += 1;
                }
                for pair in row.windows(2) {
                    after[pair[0]][pair[1]] += 1;
                }
            }
            let after_each = if n.is_multiple_of(2) { 1 } else { 2 };
            for a in 0..n {
                assert!(
                    places[a].iter().all(|&c| c == rows / n),
                    "n = {n}: places of {a}: {:?}",
                    places[a]
                );
                for b in (0..n).filter(|&b| b != a) {
                    assert_eq!(after[a][b], after_each, "n = {n}: {b} right after {a}");
                }
            }
            assert!(
                balanced_order(rows, n).eq(balanced_order(0, n)),
                "n = {n}: the orders cycle"
            );
        }
    }
}
