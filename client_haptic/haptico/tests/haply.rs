//! The Inverse3 path at its protocol boundary: a local WebSocket service that speaks the Haply Inverse
//! Service's messages (built from the `haply` crate's own types) streams states at about 1 kHz and
//! answers forces. No hardware: what a real service and device do beyond these messages is untested.

use std::time::{Duration, Instant};

use glam::Vec3;
use haptic_common::ForceTorque;
use haptico::haply::{self, HaplyStatus};
use haptico::{Device, HapticoError, presets};

#[path = "support/haply_service.rs"]
mod haply_service;
use haply_service::{FakeService, Script};

const CENTRE_AT: Vec3 = Vec3::new(0.0, 0.06, 0.07);

fn figures(status: &HaplyStatus, over: Duration) -> String {
    let (n, mean, max) = status.round_trips();
    format!(
        "{:.0} state frames/s, {:.0} force commands/s, {n} force round trips: mean {:.0} µs, max {max} µs",
        status.frames() as f64 / over.as_secs_f64(),
        status.commands() as f64 / over.as_secs_f64(),
        mean.unwrap_or(f64::NAN)
    )
}

#[test]
fn the_inverse3_is_read_and_commanded_at_the_services_rate_through_its_messages() {
    let service = FakeService::start(Script { inverse3: true, close_after: None, wander: false });
    let (mut device, status) = haply::open(&service.url(), presets::inverse3(), CENTRE_AT).expect("opens");
    assert_eq!(service.seen.lock().unwrap().profile.as_deref(), Some("phantom-heist"), "the session is named");
    // Centred: the resting grip is where the device frame was asked to put it.
    let at_rest = device.read_state(0).pose.translation;
    assert!((at_rest - CENTRE_AT).length() < 1e-4, "centred at {at_rest}");
    let clock = haptico::HapticClock::new();
    let (start, frames0) = (Instant::now(), status.frames());
    let mut latest = at_rest;
    let mut i = 0u32;
    while start.elapsed() < Duration::from_millis(1500) {
        latest = device.read_state(clock.now_us()).pose.translation;
        // A force that changes every 50 ticks, up (ours) and to the right.
        let f = Vec3::new(0.1, 1.0 + (i / 50) as f32 * 0.01, 0.0);
        device.command(ForceTorque { force: f, torque: Vec3::ZERO });
        i += 1;
        std::thread::sleep(Duration::from_micros(900));
    }
    let over = start.elapsed();
    println!("Inverse3 through a local service: {}", figures(&status, over));
    // The grip moved right in Haply's frame: right in ours, by the same metres.
    assert!(latest.x > CENTRE_AT.x + 0.005, "the grip's motion arrives: {latest}");
    assert!((latest.y - CENTRE_AT.y).abs() < 1e-4 && (latest.z - CENTRE_AT.z).abs() < 1e-4, "{latest}");
    // Up (ours) reached the service as Haply's z.
    let last = service.seen.lock().unwrap().last_force.expect("forces reached the service");
    assert!((last.z - (1.0 + ((i - 1) / 50) as f32 * 0.01)).abs() < 0.02 && (last.x - 0.1).abs() < 1e-6, "{last:?}");
    // At the service's pace: one command a state frame (about 1 kHz here), never a burst.
    let rate = (status.frames() - frames0) as f64 / over.as_secs_f64();
    assert!(rate > 300.0, "{rate:.0} frames/s");
    let (n, mean, _) = status.round_trips();
    assert!(n > 3 && mean.is_some(), "round trips measured: {n}");
    assert!(!status.disconnected());
    device.release();
    // Let go: the last command the service reads is no force.
    let start = Instant::now();
    let zero = || service.seen.lock().unwrap().last_force.is_some_and(|f| f.x == 0.0 && f.y == 0.0 && f.z == 0.0);
    while !zero() {
        assert!(start.elapsed() < Duration::from_secs(1), "{:?}", service.seen.lock().unwrap().last_force);
        std::thread::sleep(Duration::from_millis(5));
    }
}

#[test]
fn a_service_that_goes_away_mid_session_stops_forces_and_is_flagged_without_panic() {
    let service = FakeService::start(Script { inverse3: true, close_after: Some(900), wander: false });
    let (mut device, status) = haply::open(&service.url(), presets::inverse3(), CENTRE_AT).expect("opens");
    let clock = haptico::HapticClock::new();
    let start = Instant::now();
    // The haptic side goes on ticking, as the haptic thread would, while the service closes.
    while !status.disconnected() {
        assert!(start.elapsed() < Duration::from_secs(5), "the close is noticed");
        device.read_state(clock.now_us());
        device.command(ForceTorque { force: Vec3::Y, torque: Vec3::ZERO });
        std::thread::sleep(Duration::from_millis(1));
    }
    let commands = status.commands();
    for _ in 0..100 {
        device.read_state(clock.now_us());
        device.command(ForceTorque { force: Vec3::Y, torque: Vec3::ZERO });
        std::thread::sleep(Duration::from_millis(1));
    }
    assert_eq!(status.commands(), commands, "no force is sent after the service went away");
    // The state goes stale: its stamp stays behind the haptic clock.
    let now = clock.now_us();
    let stale = device.read_state(now);
    assert!(now - stale.timestamp_us > 50_000, "stamped {} µs before now", now - stale.timestamp_us);
    let t = Instant::now();
    device.release();
    assert!(t.elapsed() < Duration::from_secs(1), "letting go of a lost device takes {:?}", t.elapsed());
}

fn refused(url: &str) -> (String, Duration) {
    let start = Instant::now();
    let Err(e) = haply::open(url, presets::inverse3(), CENTRE_AT) else { panic!("opened at {url}") };
    (e.to_string(), start.elapsed())
}

#[test]
fn a_closed_port_is_refused_within_seconds_saying_to_start_the_service() {
    let port = std::net::TcpListener::bind("127.0.0.1:0").expect("binds").local_addr().expect("address").port();
    let (e, took) = refused(&format!("ws://127.0.0.1:{port}/"));
    assert!(e.contains("no Haply Inverse Service at ws://127.0.0.1:") && e.contains("start the service"), "{e}");
    assert!(!e.contains('\n'), "one line: {e}");
    assert!(took < Duration::from_secs(4), "{took:?}");
    let (e, _) = refused("not a url");
    assert!(e.contains("Haply Inverse Service at not a url"), "{e}");
}

#[test]
fn a_service_that_lists_no_inverse3_is_refused_saying_what_to_check() {
    let service = FakeService::start(Script { inverse3: false, close_after: None, wander: false });
    let (e, took) = refused(&service.url());
    assert!(e.contains("no Inverse3") && e.contains("plug it in"), "{e}");
    assert!(took < Duration::from_secs(5), "{took:?}");
    assert!(matches!(haply::open(&service.url(), presets::inverse3(), CENTRE_AT), Err(HapticoError::NoDevice { .. })));
}

#[test]
fn a_grip_that_moves_while_it_is_centred_is_refused_and_told_to_hold_still() {
    let service = FakeService::start(Script { inverse3: true, close_after: None, wander: true });
    let (e, _) = refused(&service.url());
    assert!(e.contains("hold it still"), "{e}");
}

#[test]
fn a_running_service_is_probed_for_its_devices() {
    let service = FakeService::start(Script { inverse3: true, close_after: None, wander: false });
    let listed = haply::probe(&service.url(), Duration::from_secs(2)).expect("probes");
    assert_eq!(listed.len(), 1);
    assert_eq!(listed[0].device_id, "049D");
    assert!(listed[0].calibrated && listed[0].ready);
}
