//! Benches live in `benches/`.

/// The exponent b of a least-squares fit y = a x^b to `points` (x, y), in
/// log-log coordinates: how a cost grows with a size.
pub fn fit_exponent(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (mx, my) = points.iter().fold((0.0, 0.0), |(a, b), &(x, y)| {
        (a + x.ln() / n, b + y.ln() / n)
    });
    let (sxy, sxx) = points.iter().fold((0.0, 0.0), |(a, b), &(x, y)| {
        (a + (x.ln() - mx) * (y.ln() - my), b + (x.ln() - mx).powi(2))
    });
    sxy / sxx
}

/// The bunny rooms (`data/bunny_room_N.obj`, made by
/// `data/make_bunny_rooms.py`, and the whole bunny's
/// `scenes/bunny_room.obj`) whose bunnies have at most `max` triangles and
/// are among `sizes` (the whole one: 3 674), smallest first, with their
/// bunnies' triangle counts.
pub fn bunny_rooms(sizes: &[usize], max: usize) -> Vec<(usize, std::path::PathBuf)> {
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut sizes: Vec<usize> = sizes.iter().copied().filter(|&n| n <= max).collect();
    sizes.sort_unstable();
    sizes
        .into_iter()
        .map(|n| match n {
            3674 => (n, root.join("../scenes/bunny_room.obj")),
            _ => (n, root.join(format!("data/bunny_room_{n}.obj"))),
        })
        .collect()
}
