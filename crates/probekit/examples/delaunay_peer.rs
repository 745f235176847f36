//! Writes the benchmark point sets (100 k uniform random, 47³ grid) as raw
//! little-endian `f32` xyz files into DIR and times `tetrahedralize` on them
//! (best of 5; one run for the 1 M set), printing one JSON line per set. `scripts/bench_qhull.py` runs
//! this, then SciPy's Qhull on the same files, and prints the comparison.
//!
//! Usage: `cargo run --release -p probekit --example delaunay_peer -- DIR [SETS]`
//! where the optional `SETS` is a comma-separated subset of the set names
//! (e.g. `grid_47`, for profiling one set).

use probekit::delaunay::{bench_points, predicates, tetrahedralize};
use std::io::Write;
use std::time::Instant;

/// Nanoseconds this thread has run on a CPU (Linux `/proc/thread-self/schedstat`,
/// first field), or `None` elsewhere. On a shared, overloaded machine this is a
/// better estimate of single-core speed than wall-clock time, which also counts
/// time spent waiting for a core.
fn thread_cpu_ns() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    s.split_whitespace().next()?.parse().ok()
}

/// FNV-1a over the output tetrahedra and neighbours, so that runs of two
/// builds can be compared for identical output.
fn output_hash(t: &probekit::delaunay::Tetrahedralization) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for x in t.tets.iter().chain(&t.neighbors).flatten() {
        for b in x.to_le_bytes() {
            h = (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3);
        }
    }
    h
}

fn main() -> std::io::Result<()> {
    let dir = std::path::PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| ".".into()));
    std::fs::create_dir_all(&dir)?;
    let only: Option<Vec<String>> = std::env::args()
        .nth(2)
        .map(|s| s.split(',').map(str::to_owned).collect());
    for (name, pts) in [
        ("random_100k", bench_points::uniform(100_000, 1)),
        ("grid_47", bench_points::grid(47)),
        ("random_1m", bench_points::uniform(1_000_000, 5)),
    ] {
        if only.as_ref().is_some_and(|o| !o.iter().any(|s| s == name)) {
            continue;
        }
        let path = dir.join(format!("{name}.f32"));
        let mut f = std::io::BufWriter::new(std::fs::File::create(&path)?);
        for p in &pts {
            for c in p.to_array() {
                f.write_all(&c.to_le_bytes())?;
            }
        }
        f.flush()?;
        let mut best = f64::INFINITY;
        let mut best_cpu = f64::INFINITY;
        let mut result = None;
        let runs = if pts.len() > 200_000 { 1 } else { 5 };
        for _ in 0..runs {
            let c0 = thread_cpu_ns();
            let t0 = Instant::now();
            let t = tetrahedralize(&pts).expect("valid points");
            best = best.min(t0.elapsed().as_secs_f64());
            if let (Some(a), Some(b)) = (c0, thread_cpu_ns()) {
                best_cpu = best_cpu.min((b - a) as f64 * 1e-9);
            }
            result = Some(t);
        }
        let t = result.unwrap();
        let zero = t
            .tets
            .iter()
            .filter(|v| {
                let q = v.map(|i| pts[i as usize].as_dvec3().to_array());
                predicates::orient3d(&q[0], &q[1], &q[2], &q[3])
                    != predicates::Orientation::Positive
            })
            .count();
        println!(
            "{{\"set\":\"{name}\",\"points\":{},\"tets\":{},\"seconds\":{best:.4},\"points_per_s\":{:.0},\"non_positive_tets\":{zero},\"cpu_seconds\":{best_cpu:.4},\"points_per_cpu_s\":{:.0},\"output_hash\":\"{:016x}\"}}",
            pts.len(),
            t.tets.len(),
            pts.len() as f64 / best,
            pts.len() as f64 / best_cpu,
            output_hash(&t)
        );
    }
    Ok(())
}
