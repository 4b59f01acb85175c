//! `report.json` (schema 1): the run's header (command, wall time, time budget, the Mesa
//! build and every driver) and one object per run, the README's promised fields at top level,
//! then everything else; a merged run adds `shards`, one row per shard it was put together
//! from.

use crate::model::{Metrics, RunResult, TimeBudget};

/// The document; `header` holds `mesa_build` and `drivers` as the orchestrator found them.
pub fn report(
    results: &[RunResult],
    header: &serde_json::Value,
    budget: &TimeBudget,
) -> serde_json::Value {
    let runs: Vec<serde_json::Value> = results
        .iter()
        .map(|r| {
            let m = r.metrics.as_ref();
            let rate = |n: fn(&Metrics) -> u64| {
                m.map(|m| {
                    if m.judged == 0 {
                        0.0
                    } else {
                        n(m) as f64 / m.judged as f64
                    }
                })
            };
            serde_json::json!({
                "case": r.case,
                "file": r.file,
                "backend": r.backend,
                "golden": r.golden,
                "status": r.status.name(),
                "reason": r.reason,
                "false_shadow": rate(|m| m.false_shadow),
                "false_light": rate(|m| m.false_light),
                "agreement": m.and_then(|m| m.agreement),
                "ssim": m.and_then(|m| m.ssim),
                "ssim_golden": m.and_then(|m| m.ssim_golden),
                "time_ms": r.time_s * 1e3,
                "name": r.name,
                "metrics": r.metrics,
                "failed": r.failed,
                "diagnosis": r.diagnosis,
                "reproduce": r.reproduce,
                "stderr": (!r.stderr.is_empty()).then_some(&r.stderr),
            })
        })
        .collect();
    let mut doc = serde_json::json!({
        "schema": 1,
        "wall_s": budget.wall_s,
        "time_budget": budget,
        "harness_overhead_share": budget.overhead_share(),
        "command": std::env::args().collect::<Vec<_>>().join(" "),
        "mesa_build": header["mesa_build"],
        "drivers": header["drivers"],
        "runs": runs,
    });
    // A merged run (`umbra merge`): the shards it was put together from.
    if !header["shards"].is_null() {
        doc["shards"] = header["shards"].clone();
    }
    doc
}
