//! Image metrics on linear values, the definitions `caustic converge` uses
//! (docs/commands.md).

use caustic::film::Film;

/// The film's channels as one list: R, G, B of every pixel in order.
pub fn channels(film: &Film) -> Vec<f64> {
    film.pixels.iter().flat_map(|p| p.to_array()).map(f64::from).collect()
}

/// Root-mean-square difference: sqrt(mean over i of (aᵢ − bᵢ)²).
pub fn rmse(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len(), "images of different sizes");
    (a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / a.len() as f64).sqrt()
}

/// Relative MSE of `a` against the reference `b`: the mean of
/// (a − b)² / (b² + ε) with ε = 1e-2 (Rousselle, Knaus and Zwicker 2011),
/// as `caustic converge` reports it.
pub fn relmse<T: Copy + Into<f64>>(a: &[T], b: &[T]) -> f64 {
    assert_eq!(a.len(), b.len(), "images of different sizes");
    let e = |x: f64, r: f64| (x - r).powi(2) / (r * r + 1e-2);
    a.iter().zip(b).map(|(&x, &r)| e(x.into(), r.into())).sum::<f64>() / a.len() as f64
}

/// RMSE between two films over every pixel and channel.
pub fn film_rmse(a: &Film, b: &Film) -> f64 {
    assert_eq!((a.width, a.height), (b.width, b.height), "films of different sizes");
    rmse(&channels(a), &channels(b))
}

/// The per-index mean of several images of one size.
pub fn mean_of(images: &[Vec<f64>]) -> Vec<f64> {
    (0..images[0].len())
        .map(|i| images.iter().map(|im| im[i]).sum::<f64>() / images.len() as f64)
        .collect()
}
