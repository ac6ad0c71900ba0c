fn main() {
    for spec in ["sorting", "handover"] {
        let s = pacs_baselines::bench::shield_scenario(
            spec,
            pacs_shield::shield::FilterMode::Pacs,
            20000,
        );
        println!(
            "{} median {:.1} us p90 {:.1} p99 {:.1} max {:.1} verified {:.3} chunk median {:.1} us max {:.1}",
            s.scenario,
            s.median * 1e6,
            s.p90 * 1e6,
            s.p99 * 1e6,
            s.max * 1e6,
            s.verified_fraction,
            s.chunk_median * 1e6,
            s.chunk_max * 1e6
        );
    }
}
