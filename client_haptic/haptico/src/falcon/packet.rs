//! The Falcon firmware's 16-byte packets, both ways.
//!
//! You need this module to talk to a Falcon whose firmware is loaded: every exchange is one packet out
//! (three motor commands, LEDs, the homing request) and one back (three encoder counts, grip buttons,
//! which arms are homed). A packet is framed by `<` and `>`; in between each byte carries four bits
//! plus 0x41 (`A`), a 16-bit value taking four bytes, low nibble first. Layout as documented by the
//! libnifalcon project (facts only; the code here is ours).

/// Bytes in a packet, either way.
pub const PACKET_LEN: usize = 16;
const START: u8 = b'<';
const END: u8 = b'>';
const NIBBLE: u8 = 0x41;

/// The LEDs on the Falcon's body (bits of [`Command::leds`]).
pub mod led {
    /// Green.
    pub const GREEN: u8 = 0x02;
    /// Blue.
    pub const BLUE: u8 = 0x04;
    /// Red.
    pub const RED: u8 = 0x08;
}

/// The buttons of the standard four-button grip (bits of [`Reply::buttons`]).
pub mod button {
    /// The "+" button.
    pub const PLUS: u8 = 0x1;
    /// The forward button.
    pub const FORWARD: u8 = 0x2;
    /// The centre button.
    pub const CENTRE: u8 = 0x4;
    /// The "−" button.
    pub const MINUS: u8 = 0x8;
}

/// What the host sends each exchange.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Command {
    /// Motor commands of the three arms (top, right, left), firmware units.
    pub motors: [i16; 3],
    /// LED bits ([`led`]).
    pub leds: u8,
    /// Asks the firmware to home (set in every packet until all three arms report homed).
    pub homing: bool,
}

/// What the Falcon sends back.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Reply {
    /// Encoder counts of the three arms.
    pub encoders: [i16; 3],
    /// Grip button bits ([`button`]).
    pub buttons: u8,
    /// Whether each arm (top, right, left) has found its home.
    pub homed: [bool; 3],
}

impl Reply {
    /// True when all three arms are homed.
    pub fn all_homed(&self) -> bool {
        self.homed.iter().all(|h| *h)
    }
}

/// Why a received packet was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum PacketError {
    /// The packet does not start with `<` and end with `>` (a partial or shifted read).
    #[error("Falcon packet not framed by '<' and '>' (first byte {first:#04x}, last {last:#04x})")]
    Framing {
        /// The first byte seen.
        first: u8,
        /// The last byte seen.
        last: u8,
    },
    /// A byte that should carry four bits is outside 0x41..=0x50.
    #[error("Falcon packet byte {index} is {value:#04x}, not a nibble (0x41..=0x50)")]
    Nibble {
        /// Position in the packet.
        index: usize,
        /// The byte.
        value: u8,
    },
}

/// The packet for `command`.
pub fn encode(command: &Command) -> [u8; PACKET_LEN] {
    let mut p = [NIBBLE; PACKET_LEN];
    p[0] = START;
    for (arm, value) in command.motors.iter().enumerate() {
        let v = *value as u16;
        for n in 0..4 {
            p[1 + 4 * arm + n] = NIBBLE + ((v >> (4 * n)) & 0xF) as u8;
        }
    }
    p[13] = NIBBLE + ((command.leds & 0x0E) | u8::from(command.homing));
    p[15] = END;
    p
}

/// The reply in `packet`, or why it is not one.
pub fn decode(packet: &[u8; PACKET_LEN]) -> Result<Reply, PacketError> {
    if packet[0] != START || packet[PACKET_LEN - 1] != END {
        return Err(PacketError::Framing { first: packet[0], last: packet[PACKET_LEN - 1] });
    }
    let mut encoders = [0i16; 3];
    for (arm, value) in encoders.iter_mut().enumerate() {
        let mut v = 0u16;
        for n in 0..4 {
            let index = 1 + 4 * arm + n;
            let b = packet[index];
            if !(NIBBLE..NIBBLE + 16).contains(&b) {
                return Err(PacketError::Nibble { index, value: b });
            }
            v |= u16::from(b - NIBBLE) << (4 * n);
        }
        *value = v as i16;
    }
    let status = packet[13].wrapping_sub(NIBBLE);
    let homed_bits = (status >> 4) & 0x7;
    Ok(Reply {
        encoders,
        buttons: status & 0x0F,
        homed: [homed_bits & 1 != 0, homed_bits & 2 != 0, homed_bits & 4 != 0],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_packet_captured_from_novints_sdk_decodes_to_its_three_values() {
        // From libnifalcon's util/translate_packet.py (a force command of the SDK): 4095, 3906, 4034.
        let p = [0x3c, 0x50, 0x50, 0x50, 0x41, 0x43, 0x45, 0x50, 0x41, 0x43, 0x4d, 0x50, 0x41, 0x45, 0x41, 0x3e];
        assert_eq!(decode(&p).expect("framed").encoders, [4095, 3906, 4034]);
    }

    #[test]
    fn values_are_signed_sixteen_bits_low_nibble_first() {
        // 4A 46 4B 50: nibbles 9, 5, A, F → 0xFA59 = −1447.
        let mut p = encode(&Command::default());
        p[1..5].copy_from_slice(&[0x4A, 0x46, 0x4B, 0x50]);
        assert_eq!(decode(&p).expect("framed").encoders[0], -1447);
    }

    #[test]
    fn every_command_survives_a_round_trip_through_the_layout() {
        for motors in [[0, 0, 0], [1, -1, i16::MAX], [i16::MIN, 12345, -4096]] {
            let p = encode(&Command { motors, leds: led::GREEN, homing: true });
            assert_eq!((p[0], p[15]), (b'<', b'>'));
            assert_eq!(decode(&p).expect("framed").encoders, motors);
            // LEDs and the homing request share byte 13.
            assert_eq!(p[13], 0x41 + (led::GREEN | 0x01));
        }
    }

    #[test]
    fn buttons_and_homed_arms_come_back_in_byte_thirteen() {
        let mut p = encode(&Command::default());
        p[13] = 0x41 + (0x50 | button::CENTRE);
        let r = decode(&p).expect("framed");
        assert_eq!(r.buttons, button::CENTRE);
        assert_eq!(r.homed, [true, false, true]);
        assert!(!r.all_homed());
        p[13] = 0x41 + 0x70;
        assert!(decode(&p).expect("framed").all_homed());
    }

    #[test]
    fn a_shifted_or_corrupt_packet_is_refused_with_where_it_went_wrong() {
        let good = encode(&Command::default());
        let mut shifted = [0u8; PACKET_LEN];
        shifted[1..].copy_from_slice(&good[..PACKET_LEN - 1]);
        assert_eq!(decode(&shifted), Err(PacketError::Framing { first: 0, last: b'A' }));
        let mut bad = good;
        bad[6] = 0x20;
        let e = decode(&bad).expect_err("refused");
        assert_eq!(e, PacketError::Nibble { index: 6, value: 0x20 });
        assert!(e.to_string().contains("byte 6"), "{e}");
    }
}
