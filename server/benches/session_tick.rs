//! CPU cost of one server tick (one `App::update`: receive, 60 Hz simulation step, mirror, send) with
//! both bots connected over loopback UDP, measured mid-heist. Only the server's update is timed; the
//! bot clients are stepped between samples, outside the measurement.
//!
//! Run: `cargo bench -p heist_server --bench session_tick`

use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group, criterion_main};
use heist_bots::ViveStyle;
use heist_server::ServerOptions;
use heist_server::demo::Heist;

fn session_tick(c: &mut Criterion) {
    let mut group = c.benchmark_group("server");
    for (name, style) in [("tick_with_careful_bots", ViveStyle::Careful), ("tick_with_idle_bots", ViveStyle::Idle)] {
        let fresh = || {
            let mut options = ServerOptions::local_test(6);
            options.game.time_limit_s = Some(1.0e6);
            let mut heist = Heist::start(options, style).expect("heist starts");
            for _ in 0..600 {
                heist.step(); // ten seconds in: everyone connected, heist under way
            }
            heist
        };
        let mut heist = fresh();
        group.bench_function(name, |b| {
            b.iter_custom(|iters| {
                let mut total = Duration::ZERO;
                for _ in 0..iters {
                    if !heist.server.game().is_running() {
                        heist = fresh(); // only running sessions are measured
                    }
                    let t = Instant::now();
                    heist.server.update();
                    total += t.elapsed();
                    heist.vive.update();
                    heist.phantom.update();
                }
                total
            })
        });
    }
    group.finish();
}

criterion_group!(benches, session_tick);
criterion_main!(benches);
