//! The spoken description of a target's real copy, read to Phantom at the start of the heist.

use serde::{Deserialize, Serialize};

use super::kind::{ArtifactKind, CopyTraits, MaterialClass};

/// What Phantom is told about the real copy of one target: the facts, and the sentence to speak.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Briefing {
    /// Which artifact.
    pub kind: ArtifactKind,
    /// The real copy's number of points / ridges / notches.
    pub feature_count: u32,
    /// The real copy's material.
    pub material: MaterialClass,
    /// Natural spoken English, numbers in words.
    pub text: String,
}

/// The briefing describing the real copy `real`, with its spoken text.
///
/// For example: "The real crown has seven points. It feels hard and smooth, like polished gold."
pub fn briefing(real: &CopyTraits) -> Briefing {
    let (one, many) = real.kind.feature_noun();
    let noun = if real.feature_count == 1 { one } else { many };
    let text = format!(
        "The real {} has {} {}. It feels {}, {}.",
        real.kind.name(),
        number_in_words(real.feature_count),
        noun,
        real.material.adjective(),
        real.material.simile()
    );
    Briefing { kind: real.kind, feature_count: real.feature_count, material: real.material, text }
}

/// `n` in English words ("seven", "twenty-one"); digits from one thousand up.
pub fn number_in_words(n: u32) -> String {
    const SMALL: [&str; 20] = [
        "no",
        "one",
        "two",
        "three",
        "four",
        "five",
        "six",
        "seven",
        "eight",
        "nine",
        "ten",
        "eleven",
        "twelve",
        "thirteen",
        "fourteen",
        "fifteen",
        "sixteen",
        "seventeen",
        "eighteen",
        "nineteen",
    ];
    const TENS: [&str; 10] = ["", "", "twenty", "thirty", "forty", "fifty", "sixty", "seventy", "eighty", "ninety"];
    match n {
        0..=19 => SMALL[n as usize].to_owned(),
        20..=99 if n.is_multiple_of(10) => TENS[(n / 10) as usize].to_owned(),
        20..=99 => format!("{}-{}", TENS[(n / 10) as usize], SMALL[(n % 10) as usize]),
        100..=999 if n.is_multiple_of(100) => format!("{} hundred", SMALL[(n / 100) as usize]),
        100..=999 => format!("{} hundred and {}", SMALL[(n / 100) as usize], number_in_words(n % 100)),
        _ => n.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_crown_briefing_reads_naturally() {
        let b =
            briefing(&CopyTraits { kind: ArtifactKind::Crown, feature_count: 7, material: MaterialClass::HardSmooth });
        assert_eq!(b.text, "The real crown has seven points. It feels hard and smooth, like polished gold.");
        assert_eq!((b.kind, b.feature_count, b.material), (ArtifactKind::Crown, 7, MaterialClass::HardSmooth));
    }

    #[test]
    fn a_single_feature_is_singular() {
        let b =
            briefing(&CopyTraits { kind: ArtifactKind::Idol, feature_count: 1, material: MaterialClass::SoftRough });
        assert_eq!(b.text, "The real idol has one notch. It feels soft and ribbed, like combed clay.");
    }

    #[test]
    fn numbers_are_spelled_out() {
        assert_eq!(number_in_words(0), "no");
        assert_eq!(number_in_words(12), "twelve");
        assert_eq!(number_in_words(40), "forty");
        assert_eq!(number_in_words(21), "twenty-one");
        assert_eq!(number_in_words(305), "three hundred and five");
    }

    #[test]
    fn no_briefing_contains_a_digit() {
        for kind in ArtifactKind::ALL {
            for n in kind.feature_range() {
                for material in MaterialClass::ALL {
                    let b = briefing(&CopyTraits { kind, feature_count: n, material });
                    assert!(!b.text.chars().any(|c| c.is_ascii_digit()), "{}", b.text);
                }
            }
        }
    }
}
