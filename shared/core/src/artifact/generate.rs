//! Choosing the traits of one real copy and its fakes from a seed.

use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::kind::{ArtifactKind, CopyTraits, MaterialClass};

/// Fewest copies of one artifact: the real one and two fakes.
pub const MIN_COPIES: usize = 3;

/// How a fake departs from the real copy.
#[derive(Clone, Copy)]
enum Forgery {
    /// Right material, wrong count: the player must count.
    Count,
    /// Right count, wrong material: the player must feel the surface.
    Material,
    /// Both wrong.
    Both,
}

/// The seed of a heist's `target`-th target (in the level's order): its copies' traits come from
/// [`generate_copies`] with it, and their meshes from [`copy_mesh_seed`].
pub fn target_seed(heist_seed: u64, target: usize) -> u64 {
    heist_seed.wrapping_mul(0x9E37_79B9_7F4A_7C15).wrapping_add(target as u64)
}

/// The seed of the mesh of a target's `copy`-th copy (in [`generate_copies`]'s order).
pub fn copy_mesh_seed(target_seed: u64, copy: usize) -> u64 {
    target_seed.wrapping_add(copy as u64 * 7919)
}

/// Generates the traits of `count` copies and the index of the real one; deterministic for a seed.
///
/// `count` is raised to [`MIN_COPIES`] if smaller. Every fake differs from the real copy in its feature count, its material or both; the
/// first two fakes share the material and the count of the real one respectively, so both must be
/// checked. Copies are pairwise distinct while the kind allows it.
pub fn generate_copies(kind: ArtifactKind, seed: u64, count: usize) -> (Vec<CopyTraits>, usize) {
    let count = count.max(MIN_COPIES);
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xC0B1_E5C0_B1E5_0002);
    let range = kind.feature_range();
    let real = CopyTraits {
        kind,
        feature_count: rng.random_range(range.clone()),
        material: MaterialClass::ALL[rng.random_range(0..MaterialClass::ALL.len())],
    };
    let mut copies = vec![real];
    for f in 0..count - 1 {
        let forgery = match f {
            0 => Forgery::Count,
            1 => Forgery::Material,
            _ => [Forgery::Count, Forgery::Material, Forgery::Both][rng.random_range(0..3)],
        };
        // A few tries for a fake nobody else has; a repeat is still a valid fake.
        let mut fake = forge(&real, forgery, &mut rng);
        for _ in 0..16 {
            if !copies.contains(&fake) {
                break;
            }
            fake = forge(&real, forgery, &mut rng);
        }
        copies.push(fake);
    }
    copies.shuffle(&mut rng);
    let real_index = copies.iter().position(|c| *c == real).unwrap_or(0);
    (copies, real_index)
}

/// One fake of `real`, departing from it as `forgery` says.
fn forge(real: &CopyTraits, forgery: Forgery, rng: &mut ChaCha8Rng) -> CopyTraits {
    let mut fake = *real;
    if matches!(forgery, Forgery::Count | Forgery::Both) {
        let range = real.kind.feature_range();
        // Off by one or two, within the kind's range: near misses make counting matter.
        let options: Vec<u32> = (real.feature_count.saturating_sub(2)..=real.feature_count + 2)
            .filter(|n| *n != real.feature_count && range.contains(n))
            .collect();
        fake.feature_count = options[rng.random_range(0..options.len())];
    }
    if matches!(forgery, Forgery::Material | Forgery::Both) {
        let others: Vec<MaterialClass> = MaterialClass::ALL.into_iter().filter(|m| *m != real.material).collect();
        fake.material = others[rng.random_range(0..others.len())];
    }
    fake
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exactly_one_copy_has_the_real_traits_and_every_fake_differs() {
        for kind in ArtifactKind::ALL {
            for seed in 0..200 {
                for count in [3, 4, 6] {
                    let (copies, real) = generate_copies(kind, seed, count);
                    assert_eq!(copies.len(), count);
                    assert!(real < count);
                    let r = copies[real];
                    assert!(kind.feature_range().contains(&r.feature_count));
                    for (i, c) in copies.iter().enumerate() {
                        assert_eq!(c.kind, kind);
                        assert!(kind.feature_range().contains(&c.feature_count));
                        if i != real {
                            assert_ne!(*c, r, "kind {kind} seed {seed}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn some_fake_shares_the_material_and_some_fake_shares_the_count() {
        for seed in 0..100 {
            let (copies, real) = generate_copies(ArtifactKind::Crown, seed, 3);
            let r = copies[real];
            let fakes: Vec<_> = copies.iter().enumerate().filter(|(i, _)| *i != real).map(|(_, c)| *c).collect();
            assert!(fakes.iter().any(|f| f.material == r.material && f.feature_count != r.feature_count));
            assert!(fakes.iter().any(|f| f.feature_count == r.feature_count && f.material != r.material));
        }
    }

    #[test]
    fn the_same_seed_gives_the_same_copies_and_seeds_vary_them() {
        assert_eq!(generate_copies(ArtifactKind::Idol, 9, 4), generate_copies(ArtifactKind::Idol, 9, 4));
        let distinct: std::collections::HashSet<_> =
            (0..50).map(|s| generate_copies(ArtifactKind::Idol, s, 4)).collect();
        assert!(distinct.len() > 10);
    }

    #[test]
    fn the_real_copy_is_not_always_in_the_same_place() {
        let places: std::collections::HashSet<_> =
            (0..50).map(|s| generate_copies(ArtifactKind::Amphora, s, 3).1).collect();
        assert_eq!(places.len(), 3);
    }

    #[test]
    fn too_few_copies_are_raised_to_three() {
        assert_eq!(generate_copies(ArtifactKind::Crown, 1, 0).0.len(), MIN_COPIES);
    }
}
