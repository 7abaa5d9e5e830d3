//! Feels every copy of each artifact for the given seeds through the real haptic loop (sim device) and
//! prints what touch found next to the truth: the figures behind the touch bot's thresholds.
//!
//!     cargo run --release -p client_haptic --no-default-features --example feel_copies -- 3 5 7

use client_haptic::explore::feel;
use client_haptic::haptics::{Haptics, HapticsSettings};
use heist_shared::artifact::{ArtifactKind, build_mesh, generate_copies};
use heist_shared::protocol::{ItemId, WorkbenchCopy};

fn main() -> anyhow::Result<()> {
    let seeds: Vec<u64> = std::env::args().skip(1).map(|a| a.parse()).collect::<Result<_, _>>()?;
    let mut h = Haptics::start(HapticsSettings::default())?;
    std::thread::sleep(std::time::Duration::from_millis(2500));
    println!("kind,seed,count,material,felt_count,felt_material,stiffness_n_per_m,pressure_n_per_m2,friction");
    let mut item = 0;
    for &seed in &seeds {
        for kind in ArtifactKind::ALL {
            let (copies, _) = generate_copies(kind, seed, 3);
            for t in &copies {
                item += 1;
                let copy =
                    WorkbenchCopy { item: ItemId(item), mesh: build_mesh(t, seed), material: t.material.material() };
                let f = feel(&mut h, &copy, kind).map_err(anyhow::Error::msg)?;
                println!(
                    "{kind:?},{seed},{},{:?},{},{:?},{:.0},{:.0},{:.2}",
                    t.feature_count,
                    t.material,
                    f.feature_count,
                    f.material,
                    f.stiffness_n_per_m,
                    f.pressure_n_per_m2,
                    f.friction
                );
            }
        }
    }
    h.stop();
    Ok(())
}
