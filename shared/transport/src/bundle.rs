//! Several renet packets in one netcode payload, so one datagram a frame carries what renet sends.
//!
//! renet gives each channel's messages a packet of their own and its acks one more, and netcode seals
//! every payload into a datagram of its own: a player's frame was two or three datagrams each way, each
//! one sealed, sent and opened on its own and each one a system call. Both intakes put renet's packets of
//! a frame in as few payloads as fit ([`Bundler`]) and take them out again ([`unbundle`]) before renet
//! sees them, so neither renet nor netcode changes.
//!
//! A bundle is one or more frames, each a renet packet preceded by its length (two bytes,
//! little-endian), at most [`MAX_BUNDLE_BYTES`] in all and [`MAX_PACKETS_PER_BUNDLE`] packets. The wire
//! format is the protocol's: a peer that does not bundle cannot talk to one that does (the game's
//! `PROTOCOL_ID` changed with it).

use renetcode::NETCODE_MAX_PAYLOAD_BYTES;

use crate::error::PayloadRefusal;

/// Largest bundle: netcode's largest payload, bytes.
pub const MAX_BUNDLE_BYTES: usize = NETCODE_MAX_PAYLOAD_BYTES;
/// Most renet packets in one bundle (a frame sends a few: one a channel with something to send, and
/// the acks); a bundle announcing more is refused whole.
pub const MAX_PACKETS_PER_BUNDLE: usize = 32;
/// The length before each packet, bytes.
const LENGTH_BYTES: usize = 2;

/// Packs a frame's renet packets into bundles, reusing one buffer (no allocation once it has grown).
#[derive(Debug, Default)]
pub struct Bundler {
    buffer: Vec<u8>,
}

impl Bundler {
    /// A bundler with room for the largest bundle.
    pub fn new() -> Self {
        Self { buffer: Vec::with_capacity(MAX_BUNDLE_BYTES) }
    }

    /// Puts `packets` into as few bundles as fit, in order, and hands each to `seal`; stops at `seal`'s
    /// first error. A packet too large for a bundle of its own (never one of renet's: its slices are
    /// 1,200 bytes) is handed over alone, still framed, for netcode to refuse.
    pub fn pack<P: AsRef<[u8]>, E>(
        &mut self,
        packets: impl IntoIterator<Item = P>,
        mut seal: impl FnMut(&[u8]) -> Result<(), E>,
    ) -> Result<(), E> {
        self.buffer.clear();
        let mut held = 0;
        for packet in packets {
            let packet = packet.as_ref();
            let full =
                self.buffer.len() + LENGTH_BYTES + packet.len() > MAX_BUNDLE_BYTES || held == MAX_PACKETS_PER_BUNDLE;
            if full && held > 0 {
                seal(&self.buffer)?;
                self.buffer.clear();
                held = 0;
            }
            push_frame(&mut self.buffer, packet);
            held += 1;
        }
        if held > 0 {
            seal(&self.buffer)?;
        }
        Ok(())
    }
}

/// `packet` alone in a bundle (tests, and a peer that sends one packet at a time).
pub fn single(packet: &[u8]) -> Vec<u8> {
    let mut bundle = Vec::with_capacity(LENGTH_BYTES + packet.len());
    push_frame(&mut bundle, packet);
    bundle
}

/// Appends `packet` after its length (cut at 65,535 bytes, which no bundle reaches).
fn push_frame(bundle: &mut Vec<u8>, packet: &[u8]) {
    let length = u16::try_from(packet.len()).unwrap_or(u16::MAX);
    bundle.extend_from_slice(&length.to_le_bytes());
    bundle.extend_from_slice(&packet[..usize::from(length)]);
}

/// The first frame of `rest`: its packet and what follows, or why it is not whole.
fn split_frame(rest: &[u8]) -> Result<(&[u8], &[u8]), &'static str> {
    let (length, after) = rest.split_first_chunk::<LENGTH_BYTES>().ok_or("a packet's length cut short")?;
    match usize::from(u16::from_le_bytes(*length)) {
        0 => Err("an empty packet"),
        length => after.split_at_checked(length).ok_or("a packet longer than what is left of the bundle"),
    }
}

/// The renet packets in `bundle`, in order, once the whole bundle is checked: every frame whole and not
/// empty, nothing after the last, at most [`MAX_PACKETS_PER_BUNDLE`]. A bad bundle gives nothing.
pub fn unbundle(bundle: &[u8]) -> Result<Packets<'_>, PayloadRefusal> {
    let mut rest = bundle;
    let mut count = 0;
    while !rest.is_empty() {
        (_, rest) = split_frame(rest).map_err(PayloadRefusal::BadBundle)?;
        count += 1;
        if count > MAX_PACKETS_PER_BUNDLE {
            return Err(PayloadRefusal::BadBundle("more packets than a bundle may hold"));
        }
    }
    if count == 0 {
        return Err(PayloadRefusal::BadBundle("no packet"));
    }
    Ok(Packets { rest: bundle })
}

/// The packets of a checked bundle ([`unbundle`]).
#[derive(Clone, Debug)]
pub struct Packets<'a> {
    rest: &'a [u8],
}

impl<'a> Iterator for Packets<'a> {
    type Item = &'a [u8];

    fn next(&mut self) -> Option<&'a [u8]> {
        let (packet, rest) = split_frame(self.rest).ok()?;
        self.rest = rest;
        Some(packet)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn packed(packets: &[Vec<u8>]) -> Vec<Vec<u8>> {
        let mut bundles = Vec::new();
        Bundler::new()
            .pack(packets, |b| {
                bundles.push(b.to_vec());
                Ok::<_, ()>(())
            })
            .unwrap();
        bundles
    }

    #[test]
    fn a_frames_packets_travel_in_one_bundle_and_come_out_whole_and_in_order() {
        let packets = vec![vec![1; 40], vec![2; 3], vec![3; 700]];
        let bundles = packed(&packets);
        assert_eq!(bundles.len(), 1);
        assert_eq!(bundles[0].len(), 743 + 3 * LENGTH_BYTES);
        let out: Vec<&[u8]> = unbundle(&bundles[0]).unwrap().collect();
        assert_eq!(out, packets.iter().map(Vec::as_slice).collect::<Vec<_>>());
    }

    #[test]
    fn packets_past_a_bundles_size_or_count_start_the_next_one() {
        // Two 1,200-byte slices cannot share a bundle; 40 small packets fill one and start another.
        let slices = vec![vec![7; 1200], vec![8; 1200], vec![9; 10]];
        let bundles = packed(&slices);
        assert_eq!(bundles.iter().map(Vec::len).collect::<Vec<_>>(), [1202, 1202 + 12]);
        let small: Vec<Vec<u8>> = (0..40u8).map(|i| vec![i; 5]).collect();
        let bundles = packed(&small);
        assert_eq!(bundles.len(), 2);
        let out: Vec<Vec<u8>> = bundles.iter().flat_map(|b| unbundle(b).unwrap().map(<[u8]>::to_vec)).collect();
        assert_eq!(out, small);
        assert!(bundles.iter().all(|b| b.len() <= MAX_BUNDLE_BYTES));
        assert!(packed(&[]).is_empty(), "nothing to send is no bundle");
    }

    #[test]
    fn a_bundle_that_is_not_whole_gives_nothing_and_says_why() {
        let mut two = single(&[1, 2, 3]);
        two.extend(single(&[4]));
        assert!(unbundle(&two).is_ok());
        let cases: [(&[u8], &str); 5] = [
            (&[], "no packet"),
            (&[5], "cut short"),
            (&[0, 0, 1], "empty packet"),
            (&[9, 0, 1, 2], "longer than"),
            (&two[..two.len() - 1], "longer than"),
        ];
        for (bundle, why) in cases {
            let e = unbundle(bundle).expect_err("refused").to_string();
            assert!(e.contains(why), "{bundle:?}: {e}");
        }
        let crowded: Vec<u8> = (0..=MAX_PACKETS_PER_BUNDLE).flat_map(|_| single(&[1])).collect();
        assert!(unbundle(&crowded).expect_err("too many").to_string().contains("more packets"));
    }

    #[test]
    fn a_packet_too_large_for_any_bundle_goes_alone() {
        let bundles = packed(&[vec![1; 3], vec![2; MAX_BUNDLE_BYTES], vec![3; 3]]);
        assert_eq!(bundles.iter().map(Vec::len).collect::<Vec<_>>(), [5, MAX_BUNDLE_BYTES + 2, 5]);
    }
}
