//! A hall in metres for the tests and benchmarks of default paths: an
//! interior, which a default path walks inside.

use glam::DVec3;

/// Boxes `(name, min, max)`, +Y up, one a piece: a hall 48 × 24 on a floor
/// slab, walls 12 tall under a roof slab, two rows of seven columns down
/// its length, and a door 4 wide and 4 tall in its east wall.
pub fn hall() -> Vec<(String, DVec3, DVec3)> {
    let part = |name: &str, min: [f64; 3], max: [f64; 3]| (name.to_string(), DVec3::from(min), DVec3::from(max));
    let mut boxes = vec![
        part("floor", [0.0, -0.5, 0.0], [48.0, 0.0, 24.0]),
        part("roof", [0.0, 12.0, 0.0], [48.0, 12.5, 24.0]),
        part("wall_north", [0.0, 0.0, 23.5], [48.0, 12.0, 24.0]),
        part("wall_south", [0.0, 0.0, 0.0], [48.0, 12.0, 0.5]),
        part("wall_west", [0.0, 0.0, 0.5], [0.5, 12.0, 23.5]),
        part("wall_east_a", [47.5, 0.0, 0.5], [48.0, 12.0, 10.0]),
        part("wall_east_b", [47.5, 0.0, 14.0], [48.0, 12.0, 23.5]),
        part("lintel", [47.5, 4.0, 10.0], [48.0, 12.0, 14.0]),
    ];
    for row in [8.0, 16.0] {
        for k in 1..=7 {
            let x = 6.0 * f64::from(k);
            boxes.push(part(
                &format!("column_{row}_{k}"),
                [x - 0.5, 0.0, row - 0.5],
                [x + 0.5, 12.0, row + 0.5],
            ));
        }
    }
    boxes
}
