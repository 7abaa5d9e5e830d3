//! The renet packet inside a decrypted payload, checked before renet reads it.
//!
//! renet 2.0.1 trusts a slice's `slice_index` and `num_slices`: an index at or past the count, or a slice
//! of an unfinished message announcing a larger count than its first slice did, indexes past the
//! reassembly buffer (`slice_constructor.rs:41`) and panics. A [`SliceGuard`] per connection remembers the
//! count each sliced message announced and refuses every slice that disagrees, so renet only ever sees
//! slices it can place.

use std::collections::{BTreeMap, HashMap};

use crate::error::PayloadRefusal;

/// renet's slice size, bytes.
pub const SLICE_SIZE: u64 = 1200;
/// Sliced messages remembered per channel; a slice of a message older than all of them is refused.
pub const TRACKED_PER_CHANNEL: usize = 64;

const SMALL_RELIABLE: u8 = 0;
const SMALL_UNRELIABLE: u8 = 1;
const RELIABLE_SLICE: u8 = 2;
const UNRELIABLE_SLICE: u8 = 3;
const ACK: u8 = 4;

/// One slice's header.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct SliceHeader {
    reliable: bool,
    channel: u8,
    message_id: u64,
    index: u64,
    count: u64,
}

/// The sliced messages of one channel that renet may still be assembling.
#[derive(Debug, Default)]
struct ChannelSlices {
    /// Messages below this id are no longer tracked: their slices are refused.
    floor: u64,
    /// Slice count of each tracked message, by message id.
    counts: BTreeMap<u64, u64>,
}

/// Checks the renet packets of one connection.
#[derive(Debug)]
pub struct SliceGuard {
    max_slices: u64,
    channels: HashMap<(bool, u8), ChannelSlices>,
}

impl SliceGuard {
    /// A guard accepting messages of at most `max_slices` slices (`max_slices × 1200` bytes).
    pub fn new(max_slices: u64) -> Self {
        Self { max_slices, channels: HashMap::new() }
    }

    /// Checks one renet packet; on `Ok` renet may process it. Packets other than slices pass untouched:
    /// renet refuses their malformations itself, by disconnecting the sender.
    pub fn check(&mut self, packet: &[u8]) -> Result<(), PayloadRefusal> {
        let Some(slice) = slice_header(packet)? else { return Ok(()) };
        if slice.index >= slice.count {
            return Err(PayloadRefusal::SliceOutOfRange { index: slice.index, count: slice.count });
        }
        if slice.count > self.max_slices {
            return Err(PayloadRefusal::TooManySlices { count: slice.count, max: self.max_slices });
        }
        let channel = self.channels.entry((slice.reliable, slice.channel)).or_default();
        if slice.message_id < channel.floor {
            return Err(PayloadRefusal::StaleSlice(slice.message_id));
        }
        match channel.counts.get(&slice.message_id) {
            Some(&was) if was != slice.count => {
                return Err(PayloadRefusal::SliceCountChanged { message_id: slice.message_id, was, now: slice.count });
            }
            Some(_) => {}
            None => {
                if channel.counts.len() >= TRACKED_PER_CHANNEL {
                    // Forget the oldest message for good: ids only grow, and renet may still hold its
                    // buffer, so from now on its slices are refused rather than trusted.
                    if let Some((oldest, _)) = channel.counts.pop_first() {
                        channel.floor = oldest + 1;
                    }
                    if slice.message_id < channel.floor {
                        return Err(PayloadRefusal::StaleSlice(slice.message_id));
                    }
                }
                channel.counts.insert(slice.message_id, slice.count);
            }
        }
        Ok(())
    }
}

/// The slice header of a renet packet, or `None` for the other packet types.
fn slice_header(packet: &[u8]) -> Result<Option<SliceHeader>, PayloadRefusal> {
    let mut b = octets::Octets::with_slice(packet);
    let truncated = |_| PayloadRefusal::Truncated;
    let reliable = match b.get_u8().map_err(truncated)? {
        RELIABLE_SLICE => true,
        UNRELIABLE_SLICE => false,
        SMALL_RELIABLE | SMALL_UNRELIABLE | ACK => return Ok(None),
        _ => return Ok(None), // renet disconnects on an unknown type
    };
    let _sequence = b.get_varint().map_err(truncated)?;
    let channel = b.get_u8().map_err(truncated)?;
    let message_id = b.get_varint().map_err(truncated)?;
    let index = b.get_varint().map_err(truncated)?;
    let count = b.get_varint().map_err(truncated)?;
    Ok(Some(SliceHeader { reliable, channel, message_id, index, count }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A slice packet as renet writes it.
    pub(crate) fn slice(reliable: bool, channel: u8, message_id: u64, index: u64, count: u64) -> Vec<u8> {
        let mut buf = vec![0u8; 64];
        let len = {
            let mut b = octets::OctetsMut::with_slice(&mut buf);
            b.put_u8(if reliable { RELIABLE_SLICE } else { UNRELIABLE_SLICE }).unwrap();
            b.put_varint(7).unwrap();
            b.put_u8(channel).unwrap();
            b.put_varint(message_id).unwrap();
            b.put_varint(index).unwrap();
            b.put_varint(count).unwrap();
            b.put_varint(3).unwrap();
            b.put_bytes(&[1, 2, 3]).unwrap();
            b.off()
        };
        buf.truncate(len);
        buf
    }

    #[test]
    fn a_slice_past_its_count_is_refused() {
        let mut g = SliceGuard::new(16);
        assert_eq!(g.check(&slice(true, 0, 0, 5, 5)), Err(PayloadRefusal::SliceOutOfRange { index: 5, count: 5 }));
        assert_eq!(g.check(&slice(false, 0, 0, 0, 0)), Err(PayloadRefusal::SliceOutOfRange { index: 0, count: 0 }));
        assert_eq!(g.check(&slice(true, 0, 0, 4, 5)), Ok(()));
    }

    #[test]
    fn a_message_cannot_change_its_slice_count_midway() {
        let mut g = SliceGuard::new(16);
        assert_eq!(g.check(&slice(true, 1, 9, 0, 2)), Ok(()));
        assert_eq!(
            g.check(&slice(true, 1, 9, 7, 8)),
            Err(PayloadRefusal::SliceCountChanged { message_id: 9, was: 2, now: 8 })
        );
        assert_eq!(g.check(&slice(true, 1, 9, 1, 2)), Ok(()), "the rest of the message still arrives");
        assert_eq!(g.check(&slice(false, 1, 9, 7, 8)), Ok(()), "the unreliable channel counts its own ids");
    }

    #[test]
    fn oversized_messages_are_refused() {
        let mut g = SliceGuard::new(16);
        assert_eq!(g.check(&slice(true, 0, 0, 0, 17)), Err(PayloadRefusal::TooManySlices { count: 17, max: 16 }));
    }

    #[test]
    fn forgotten_messages_stay_refused() {
        let mut g = SliceGuard::new(16);
        for id in 0..TRACKED_PER_CHANNEL as u64 {
            g.check(&slice(true, 0, id, 0, 2)).unwrap();
        }
        // One more message pushes out message 0; its slices can no longer be checked, so they are refused.
        g.check(&slice(true, 0, 100, 0, 2)).unwrap();
        assert_eq!(g.check(&slice(true, 0, 0, 1, 9)), Err(PayloadRefusal::StaleSlice(0)));
        assert_eq!(g.check(&slice(true, 0, 1, 1, 2)), Ok(()));
    }

    #[test]
    fn other_packets_and_truncated_slices() {
        let mut g = SliceGuard::new(16);
        assert_eq!(g.check(&[ACK, 1, 2]), Ok(()));
        assert_eq!(g.check(&[]), Err(PayloadRefusal::Truncated));
        assert_eq!(g.check(&[RELIABLE_SLICE, 0]), Err(PayloadRefusal::Truncated));
    }
}
