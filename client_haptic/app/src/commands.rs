//! What the `join`, `practice` and `devices` commands do: the device checked first, a seat asked for by
//! speech where the command line left something out, the app run until the session ends.

use std::net::SocketAddr;
use std::time::Duration;

use heist_shared::protocol::Role;

use crate::assemble::app;
use crate::cli::{JoinArgs, PracticeArgs};
use crate::client::PhantomSettings;

/// Runs `join`: asks by speech for what the command line left out, gets a token (saying every failure
/// and what to do next, and asking again where that helps), connects, plays until the session ends.
pub fn join(args: &JoinArgs) -> anyhow::Result<()> {
    let mut settings = args.client.settings().map_err(anyhow::Error::msg)?;
    let mut prompter = crate::prompt::Prompter::new(&mut settings)?;
    check_device(&mut prompter, &settings)?;
    let cache = heist_client::SeatCache::in_default_dir();
    let joined = get_a_seat(&mut prompter, args, cache.as_ref());
    let (addr, joining) = match joined {
        Ok(j) => j,
        Err(e) => {
            prompter.finish_speaking(Duration::from_secs(30));
            return Err(e);
        }
    };
    let (audio, speaker) = prompter.into_parts();
    let mut app = app(settings, args.client.headless, None, Some((audio, speaker)))?;
    args.client.request_shot(&mut app);
    app.finish();
    app.cleanup();
    heist_client::connect(&mut app, joining.token)?;
    heist_client::hold_seat(&mut app, cache, addr, Role::Phantom);
    app.run();
    Ok(())
}

/// Looks for a real device before anything else, and says what was found and what to do with it, or what
/// is wrong (then the program ends: a seat is no use without the device).
pub fn check_device(prompter: &mut crate::prompt::Prompter, settings: &PhantomSettings) -> anyhow::Result<()> {
    match crate::device::check(&settings.haptics.device) {
        Ok(Some(setup)) => prompter.say(setup),
        Ok(None) => {}
        Err(e) => {
            let said = match &e {
                crate::ClientError::Device(why) => format!("The haptic device is not ready: {why}."),
                other => other.to_string(),
            };
            prompter.say(said);
            prompter.finish_speaking(Duration::from_secs(30));
            return Err(e.into());
        }
    }
    Ok(())
}

/// The token for a seat: from the command line's address and code, or from spoken questions.
fn get_a_seat(
    prompter: &mut crate::prompt::Prompter,
    args: &JoinArgs,
    cache: Option<&heist_client::SeatCache>,
) -> anyhow::Result<(SocketAddr, heist_client::Joining)> {
    use crate::prompt::Next;
    let asking = args.code.is_none();
    let no_answer = || anyhow::anyhow!("joining: no answer (the input ended, or the client was stopped)");
    let mut addr = args.addr;
    let mut code = args.code.clone();
    loop {
        let at = match addr {
            Some(a) => a,
            None => *addr.insert(prompter.ask_address().ok_or_else(no_answer)?),
        };
        // A kept seat is taken back without the code.
        let kept = cache.is_some_and(|c| c.load(at, Role::Phantom).is_some());
        let typed = match (&code, kept) {
            (Some(c), _) => c.clone(),
            (None, true) => String::new(),
            (None, false) => code.insert(prompter.ask_code().ok_or_else(no_answer)?).clone(),
        };
        if kept {
            prompter.say("Taking your seat back.");
        }
        let result = match heist_client::join_or_resume(at, &typed, Role::Phantom, cache, Duration::from_secs(5)) {
            // The kept seat is gone and no code was typed yet: ask for it.
            Err(heist_client::JoinError::BadCode(_)) if typed.is_empty() => {
                code = None;
                continue;
            }
            other => other,
        };
        let e = match result {
            Ok(joining) => return Ok((at, joining)),
            Err(e) => e,
        };
        let (said, next) = crate::prompt::advice(&e);
        prompter.say(said);
        let error = anyhow::Error::new(e).context(format!("joining {at} as Phantom"));
        match next {
            _ if !asking => return Err(error),
            Next::Address => addr = None,
            Next::Code => code = None,
            Next::Wait(s) => {
                prompter.finish_speaking(Duration::from_secs(30));
                std::thread::sleep(Duration::from_secs(u64::from(s.min(300))));
                code = None;
            }
            Next::Stop => return Err(error),
        }
    }
}

/// Runs `practice`: looks for a real device first, as `join` and `host` do, then feels copies on the bench.
pub fn practice(args: &PracticeArgs) -> anyhow::Result<()> {
    let mut settings = args.client.settings().map_err(anyhow::Error::msg)?;
    let mut prompter = crate::prompt::Prompter::new(&mut settings)?;
    check_device(&mut prompter, &settings)?;
    let kind = args.kind.into();
    let practice = Some(crate::practice::Practice::new(kind, args.seed));
    let mut app = app(settings, args.client.headless, practice, Some(prompter.into_parts()))?;
    args.client.request_shot(&mut app);
    app.run();
    Ok(())
}

/// Runs `devices`.
pub fn devices() -> anyhow::Result<()> {
    println!("Device presets (for --preset with the sim device):");
    for p in haptico::presets::all() {
        println!(
            "  {:<28} {:.1} N peak, {} N/m, {}",
            p.name,
            p.peak_force_n,
            p.max_stiffness_n_per_m,
            if p.renders_torque() { "forces and torques" } else { "forces only" }
        );
    }
    match haptico::hid::list_devices() {
        Ok(list) if list.is_empty() => println!("No HID haptic device found (see docs/haptics.md for the udev rule)."),
        Ok(list) => {
            println!("HID devices (for --device hid:PATH):");
            for d in list {
                println!("  {} {:04x}:{:04x} {:?} {}", d.path, d.vendor_id, d.product_id, d.kind, d.product);
            }
        }
        Err(e) => println!("HID devices could not be listed: {e}"),
    }
    match haptico::falcon::usb::count_plugged_in() {
        Ok(0) => println!("No Novint Falcon on USB."),
        Ok(n) => println!("Novint Falcon on USB ({n}): renders forces (--device falcon[:FIRMWARE])."),
        Err(e) => println!("USB devices could not be listed (for a Falcon): {e}"),
    }
    let url = haptico::haply::DEFAULT_URL;
    match haptico::haply::probe(url, Duration::from_secs(1)) {
        Ok(list) if list.is_empty() => println!("The Haply Inverse Service at {url} lists no Inverse3."),
        Ok(list) => {
            for d in list {
                println!(
                    "Haply Inverse3 {} at {url}: renders forces (--device haply){}",
                    d.device_id,
                    if d.calibrated { "" } else { "; not calibrated yet" }
                );
            }
        }
        Err(_) => println!("No Haply Inverse Service at {url} (for an Inverse3)."),
    }
    Ok(())
}
