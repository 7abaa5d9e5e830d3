//! How closely what was heard follows what was said: energy envelopes, their correlation, and the lag
//! that aligns them (the mouth-to-ear delay).
//!
//! You need this module to measure a voice path (the tests and `benches/voice_link.rs` do). Plain
//! functions over mono samples; the lag is in envelope windows.

/// The energy envelope of `x`: RMS over consecutive windows of `hop` samples.
pub fn envelope(x: &[f32], hop: usize) -> Vec<f32> {
    x.chunks(hop.max(1)).map(|c| (c.iter().map(|s| s * s).sum::<f32>() / c.len() as f32).sqrt()).collect()
}

/// Pearson's correlation of `a` and `b` over their common length (0 when either is flat).
pub fn pearson(a: &[f32], b: &[f32]) -> f32 {
    let n = a.len().min(b.len());
    if n == 0 {
        return 0.0;
    }
    let (a, b) = (&a[..n], &b[..n]);
    let (ma, mb) = (a.iter().sum::<f32>() / n as f32, b.iter().sum::<f32>() / n as f32);
    let cov: f32 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: f32 = a.iter().map(|x| (x - ma).powi(2)).sum();
    let vb: f32 = b.iter().map(|y| (y - mb).powi(2)).sum();
    cov / (va * vb).sqrt().max(1e-12)
}

/// The lag (0..`max_lag` windows) at which the envelope `heard` best follows `said`, and the correlation
/// there; lags that leave less than half of `said` to compare are not tried.
pub fn align(said: &[f32], heard: &[f32], max_lag: usize) -> (usize, f32) {
    (0..max_lag)
        .filter(|lag| heard.len() > lag + said.len() / 2)
        .map(|lag| (lag, pearson(said, &heard[lag..])))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap_or((0, 0.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_delayed_copy_is_found_at_its_delay_with_full_correlation() {
        let said: Vec<f32> = (0..48_000).map(|i| ((i / 2400) % 3) as f32 * (i as f32 * 0.1).sin()).collect();
        let mut heard = vec![0.0; 4800];
        heard.extend(said.iter().map(|s| s * 0.3));
        let (lag, r) = align(&envelope(&said, 120), &envelope(&heard, 120), 100);
        assert_eq!(lag, 40, "4800 samples = 40 windows of 120");
        assert!(r > 0.99, "{r}");
        assert_eq!(pearson(&[1.0, 1.0], &[0.0, 2.0]), 0.0, "a flat signal correlates with nothing");
    }
}
