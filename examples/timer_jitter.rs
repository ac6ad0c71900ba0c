//! How late this machine wakes a 1 kHz loop that does nothing: the floor under any control loop's
//! timing (the shield's loops included). Sleeps to deadlines t_k = t_0 + k·1 ms and records how
//! late each wake-up is. Then, for as many seconds, a busy loop that only reads the clock: every
//! gap between two reads over 20 µs is the machine taking the CPU away from a running computation
//! (an interrupt, the host, another thread), which no code in the loop can avoid; `pacs bench
//! shield` measures the same floor next to every step (`floor_*`).
//!
//!     cargo run --release --example timer_jitter [-- SECONDS]
//!     chrt -f 80 cargo run --release --example timer_jitter     # under SCHED_FIFO (root)
//!
//! Compare with `stats()["max_late_us"]` of `pacs.ShieldLoop` (python/examples/realtime_loop.py):
//! a loop that adds nothing to the platform's jitter shows the same figures.

use std::time::{Duration, Instant};

fn main() {
    let seconds: f64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(10.0);
    if !(seconds >= 0.001 && seconds.is_finite()) {
        eprintln!("timer_jitter: SECONDS must be a number of at least 0.001, got {seconds}");
        std::process::exit(2);
    }
    let period = Duration::from_millis(1);
    let n = (seconds * 1000.0) as usize;
    let mut late_us = Vec::with_capacity(n);
    let t0 = Instant::now();
    for k in 0..n {
        let deadline = t0 + period * k as u32;
        let now = Instant::now();
        if deadline > now {
            std::thread::sleep(deadline - now);
        }
        late_us.push(
            Instant::now()
                .saturating_duration_since(deadline)
                .as_secs_f64()
                * 1e6,
        );
    }
    late_us.sort_by(f64::total_cmp);
    let q = |p: f64| late_us[((p * n as f64) as usize).min(n - 1)];
    let over = late_us.iter().filter(|&&x| x > 1000.0).count();
    println!(
        "{n} wake-ups at 1 kHz: late median {:.0} us, p99 {:.0} us, p99.9 {:.0} us, max {:.0} us; {over} more than one period late",
        q(0.5),
        q(0.99),
        q(0.999),
        late_us[n - 1]
    );
    // The busy loop: gaps between consecutive clock reads.
    let (mut gaps_20, mut gaps_50, mut longest) = (0usize, 0usize, 0.0f64);
    let start = Instant::now();
    let mut prev = start;
    let mut reads = 0u64;
    while prev.duration_since(start).as_secs_f64() < seconds {
        let now = Instant::now();
        let gap = now.duration_since(prev).as_secs_f64() * 1e6;
        gaps_20 += (gap > 20.0) as usize;
        gaps_50 += (gap > 50.0) as usize;
        longest = longest.max(gap);
        prev = now;
        reads += 1;
    }
    println!(
        "busy loop for {seconds} s ({reads} clock reads): interrupted {gaps_20} times for over 20 us, {gaps_50} times for over 50 us ({:.0} per second), longest {longest:.0} us",
        gaps_50 as f64 / seconds
    );
}
