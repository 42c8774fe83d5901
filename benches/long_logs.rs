//! How the cluster proposal's cost grows with the number of segments a long log gives (it grew with
//! their cube before the seeds and the relaxation steps were bounded): J segment models of 19 poles
//! and 3 zeros, a real pole and a pair shared by every segment, the rest scattered.
//! Run: `cargo bench --bench long_logs --no-default-features`.
use jetid::core::identification::cluster::{ClusterSettings, SegmentRoots};
use jetid::core::identification::cluster_proposal::propose_clusters;
use nalgebra::Complex;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn main() {
    divan::main();
}

const DT_SECS: f64 = 1.0 / 8.85;

fn segment_roots(segments: usize) -> Vec<SegmentRoots> {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut polar =
        |lo: f64, hi: f64| Complex::from_polar(rng.random_range(lo..hi), rng.random_range(0.0..3.1));
    (0..segments)
        .map(|j| {
            let pair = Complex::new(0.80, 0.21) + polar(0.0, 0.01);
            let mut poles = vec![Complex::new(0.936, 0.0) + polar(0.0, 0.005).re, pair, pair.conj()];
            for _ in 0..8 {
                let z = polar(0.05, 0.98);
                poles.extend([z, z.conj()]);
            }
            let z = polar(0.05, 1.5);
            SegmentRoots { label: format!("S{j}"), poles, zeros: vec![z, z.conj(), Complex::new(0.3, 0.0)] }
        })
        .collect()
}

#[divan::bench(args = [8, 32, 128, 512], sample_count = 3)]
fn propose(bencher: divan::Bencher, segments: usize) {
    let roots = segment_roots(segments);
    let settings = ClusterSettings::default();
    bencher.bench(|| propose_clusters(&roots, &settings, DT_SECS).map(|c| c.len()));
}
