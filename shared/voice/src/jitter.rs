//! The receiver's jitter buffer: frames arrive when the network brings them (in bursts, out of order,
//! some never); the sound card takes one every 20 ms. The buffer holds a transmission back by a playout
//! delay before it starts and plays frames in sequence. When the next frame is missing and nothing after
//! it is here either, it is probably late, not lost: the buffer conceals 20 ms and waits for it (the
//! delay grows by a frame). When frames after it are here, it is lost: rebuilt from the next frame's FEC,
//! or concealed. A frame that comes after its turn is dropped and makes the next transmission start
//! with a longer delay; a calm stretch shortens it again.
//!
//! You need this module to change the voice's latency or its behaviour under loss. Pure and
//! allocation-free: the caller's clock is the number of [`JitterBuffer::pop`] calls (one per 20 ms).

use heist_shared::protocol::voice::{MAX_VOICE_BYTES, VoiceFrame};

/// Frames the buffer can hold: 640 ms, far more than any playout delay it uses.
pub const SLOTS: usize = 32;
/// The playout delay a transmission starts with, frames (40 ms).
pub const START_DELAY: u16 = 2;
/// The longest playout delay, frames (120 ms).
pub const MAX_DELAY: u16 = 6;
/// Frames played without one coming late before the delay shrinks by one (10 s).
pub const CALM_FRAMES: u32 = 500;
/// Missing frames in a row (with nothing buffered) after which a transmission counts as over (its end
/// frame was lost): 100 ms.
pub const GIVE_UP_AFTER: u32 = 5;

/// One frame's packet, fixed-size so it moves between threads without allocating.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Packet {
    /// Sequence number.
    pub seq: u16,
    /// The transmission's last frame.
    pub end: bool,
    len: u16,
    bytes: [u8; MAX_VOICE_BYTES],
}

impl Packet {
    /// The packet of `frame`; `None` when its Opus data is empty or longer than [`MAX_VOICE_BYTES`].
    pub fn new(seq: u16, end: bool, opus: &[u8]) -> Option<Self> {
        if opus.is_empty() || opus.len() > MAX_VOICE_BYTES {
            return None;
        }
        let mut bytes = [0; MAX_VOICE_BYTES];
        bytes[..opus.len()].copy_from_slice(opus);
        Some(Self { seq, end, len: opus.len() as u16, bytes })
    }

    /// The packet of a received frame.
    pub fn of(frame: &VoiceFrame) -> Option<Self> {
        Self::new(frame.seq, frame.end, &frame.opus)
    }

    /// The Opus data.
    pub fn opus(&self) -> &[u8] {
        &self.bytes[..usize::from(self.len)]
    }
}

/// What to play for the next 20 ms.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Playout {
    /// This frame, decoded.
    Frame(Packet),
    /// A lost frame, rebuilt from the FEC data in this (the next) frame.
    Recover(Packet),
    /// A lost frame, concealed.
    Conceal,
    /// Nothing is being said.
    Silence,
}

/// What the buffer has done, counted since it was made.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct JitterStats {
    /// Frames played from their own packet.
    pub played: u32,
    /// Lost frames rebuilt from FEC.
    pub recovered: u32,
    /// Lost frames concealed.
    pub concealed: u32,
    /// Frames that arrived after their turn (dropped).
    pub late: u32,
    /// Transmissions started.
    pub transmissions: u32,
    /// The playout delay now, frames.
    pub delay: u16,
}

/// The jitter buffer (see the module docs).
#[derive(Clone, Debug)]
pub struct JitterBuffer {
    slots: [Option<Packet>; SLOTS],
    /// The next sequence number to play while a transmission plays.
    next: Option<u16>,
    /// Pops since the first frame of a waiting transmission arrived.
    waited: u16,
    missing_run: u32,
    calm: u32,
    /// The last frame played (or given up) of the last transmission: older stragglers are late.
    played_up_to: Option<u16>,
    stats: JitterStats,
}

impl Default for JitterBuffer {
    fn default() -> Self {
        Self {
            slots: [None; SLOTS],
            next: None,
            waited: 0,
            missing_run: 0,
            calm: 0,
            played_up_to: None,
            stats: JitterStats { delay: START_DELAY, ..Default::default() },
        }
    }
}

/// `a - b` in sequence space (wrapping), as a signed distance.
fn distance(a: u16, b: u16) -> i32 {
    i32::from(a.wrapping_sub(b) as i16)
}

impl JitterBuffer {
    /// What the buffer has done.
    pub fn stats(&self) -> JitterStats {
        self.stats
    }

    /// True while a transmission is playing (or waiting out its playout delay).
    pub fn is_active(&self) -> bool {
        self.next.is_some() || self.slots.iter().any(Option::is_some)
    }

    fn buffered(&self) -> usize {
        self.slots.iter().filter(|s| s.is_some()).count()
    }

    fn oldest(&self) -> Option<u16> {
        let any = self.slots.iter().flatten().next()?.seq;
        self.slots.iter().flatten().map(|p| p.seq).min_by_key(|s| distance(*s, any))
    }

    fn late(&mut self) {
        // Its turn has passed (it was rebuilt or concealed): the next transmission waits longer.
        self.stats.late += 1;
        self.stats.delay = (self.stats.delay + 1).min(MAX_DELAY);
        self.calm = 0;
    }

    /// Takes a frame that arrived.
    pub fn push(&mut self, packet: Packet) {
        if let Some(next) = self.next {
            let ahead = distance(packet.seq, next);
            if ahead < 0 {
                self.late();
                return;
            }
            if ahead >= SLOTS as i32 {
                // Far ahead of what plays: the sender started over; so does the buffer.
                self.reset();
            }
        } else if let Some(last) = self.played_up_to
            && (-(SLOTS as i32)..=0).contains(&distance(packet.seq, last))
        {
            self.late();
            return;
        } else if let Some(oldest) = self.oldest()
            && distance(packet.seq, oldest).unsigned_abs() >= SLOTS as u32
        {
            self.reset();
        }
        self.slots[usize::from(packet.seq) % SLOTS] = Some(packet);
    }

    fn reset(&mut self) {
        if let Some(next) = self.next {
            self.played_up_to = Some(next.wrapping_sub(1));
        }
        self.slots = [None; SLOTS];
        self.next = None;
        self.waited = 0;
        self.missing_run = 0;
    }

    fn take(&mut self, seq: u16) -> Option<Packet> {
        let slot = &mut self.slots[usize::from(seq) % SLOTS];
        if slot.is_some_and(|p| p.seq == seq) { slot.take() } else { None }
    }

    fn peek(&self, seq: u16) -> Option<Packet> {
        self.slots[usize::from(seq) % SLOTS].filter(|p| p.seq == seq)
    }

    /// The next 20 ms.
    pub fn pop(&mut self) -> Playout {
        let Some(next) = self.next else {
            let Some(oldest) = self.oldest() else { return Playout::Silence };
            // A transmission waits out the playout delay (counted from its first frame), unless its end
            // is already here.
            self.waited += 1;
            let has_end = self.slots.iter().flatten().any(|p| p.end);
            if self.waited <= self.stats.delay && self.buffered() < usize::from(self.stats.delay) + 1 && !has_end {
                return Playout::Silence;
            }
            self.next = Some(oldest);
            self.waited = 0;
            self.missing_run = 0;
            self.stats.transmissions += 1;
            return self.pop();
        };
        if let Some(p) = self.take(next) {
            self.next = (!p.end).then(|| next.wrapping_add(1));
            self.missing_run = 0;
            self.stats.played += 1;
            self.calm += 1;
            if self.calm >= CALM_FRAMES {
                self.calm = 0;
                self.stats.delay = (self.stats.delay - 1).max(1);
            }
            if p.end {
                self.played_up_to = Some(next);
            }
            return Playout::Frame(p);
        }
        if self.buffered() == 0 {
            // Nothing after it either: it is late rather than lost. Fill 20 ms and wait for it, until
            // the wait says the transmission is over (its end frame lost, or the sender gone).
            self.missing_run += 1;
            if self.missing_run > GIVE_UP_AFTER {
                self.reset();
                return Playout::Silence;
            }
            self.stats.concealed += 1;
            return Playout::Conceal;
        }
        // Frames after it are here: it is lost.
        self.next = Some(next.wrapping_add(1));
        match self.peek(next.wrapping_add(1)) {
            Some(after) => {
                self.stats.recovered += 1;
                Playout::Recover(after)
            }
            None => {
                self.stats.concealed += 1;
                Playout::Conceal
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(seq: u16) -> Packet {
        Packet::new(seq, false, &[seq as u8, 1, 2]).expect("packet")
    }

    fn end(seq: u16) -> Packet {
        Packet::new(seq, true, &[seq as u8]).expect("packet")
    }

    fn seq_of(out: Playout) -> Option<u16> {
        match out {
            Playout::Frame(p) => Some(p.seq),
            _ => None,
        }
    }

    #[test]
    fn a_transmission_waits_out_the_playout_delay_then_plays_in_order() {
        let mut jb = JitterBuffer::default();
        assert_eq!(jb.pop(), Playout::Silence, "nothing said");
        jb.push(p(10));
        assert_eq!(jb.pop(), Playout::Silence, "waiting: 1");
        jb.push(p(12));
        jb.push(p(11));
        // Three buffered (delay 2 + 1): it starts.
        assert_eq!(seq_of(jb.pop()), Some(10));
        assert_eq!(seq_of(jb.pop()), Some(11));
        assert_eq!(seq_of(jb.pop()), Some(12));
        jb.push(end(13));
        assert_eq!(jb.pop(), Playout::Frame(end(13)));
        assert_eq!(jb.pop(), Playout::Silence, "over");
        assert!(!jb.is_active());
        assert_eq!(jb.stats().transmissions, 1);
    }

    #[test]
    fn a_short_transmission_with_its_end_plays_at_once() {
        let mut jb = JitterBuffer::default();
        jb.push(p(0));
        jb.push(end(1));
        assert_eq!(seq_of(jb.pop()), Some(0));
        assert_eq!(seq_of(jb.pop()), Some(1));
    }

    #[test]
    fn a_lost_frame_is_rebuilt_from_the_next_and_a_late_one_lengthens_the_next_delay() {
        let mut jb = JitterBuffer::default();
        for s in [0, 1, 2, 4, 6] {
            jb.push(p(s));
        }
        assert_eq!(seq_of(jb.pop()), Some(0));
        assert_eq!(seq_of(jb.pop()), Some(1));
        assert_eq!(seq_of(jb.pop()), Some(2));
        assert_eq!(jb.pop(), Playout::Recover(p(4)), "3 is missing and 4 is here: 4 carries its FEC");
        assert_eq!(seq_of(jb.pop()), Some(4));
        assert_eq!(jb.pop(), Playout::Recover(p(6)), "5 is missing and 6 is here");
        jb.push(p(3));
        assert_eq!(jb.stats().late, 1, "3 came after its turn");
        assert_eq!(jb.stats().delay, START_DELAY + 1);
        assert_eq!(seq_of(jb.pop()), Some(6));
        assert_eq!((jb.stats().recovered, jb.stats().played), (2, 5));
    }

    #[test]
    fn an_empty_buffer_waits_for_the_late_frame_instead_of_skipping_it() {
        let mut jb = JitterBuffer::default();
        for s in 0..3 {
            jb.push(p(s));
        }
        for s in 0..3 {
            assert_eq!(seq_of(jb.pop()), Some(s));
        }
        assert_eq!(jb.pop(), Playout::Conceal, "3 is not here, nothing else is");
        assert_eq!(jb.pop(), Playout::Conceal);
        jb.push(p(3));
        assert_eq!(seq_of(jb.pop()), Some(3), "played when it came, not dropped");
        assert_eq!(jb.stats().late, 0);
    }

    #[test]
    fn a_straggler_after_the_end_is_late_not_a_new_transmission() {
        let mut jb = JitterBuffer::default();
        jb.push(p(0));
        jb.push(end(2));
        jb.push(p(1));
        for _ in 0..3 {
            assert!(seq_of(jb.pop()).is_some());
        }
        jb.push(p(1));
        assert!(!jb.is_active(), "the duplicate is dropped");
        assert_eq!(jb.stats().late, 1);
    }

    #[test]
    fn a_transmission_whose_end_was_lost_falls_silent_and_the_next_starts_afresh() {
        let mut jb = JitterBuffer::default();
        for s in 0..4 {
            jb.push(p(s));
        }
        for _ in 0..4 {
            assert!(seq_of(jb.pop()).is_some());
        }
        let fills: Vec<Playout> = (0..10).map(|_| jb.pop()).collect();
        assert!(fills[..GIVE_UP_AFTER as usize].iter().all(|o| *o == Playout::Conceal), "{fills:?}");
        assert!(fills[GIVE_UP_AFTER as usize..].iter().all(|o| *o == Playout::Silence), "{fills:?}");
        for s in 100..104 {
            jb.push(p(s));
        }
        assert_eq!(seq_of(jb.pop()), Some(100), "the next transmission starts at its own first frame");
        assert_eq!(jb.stats().transmissions, 2);
    }

    #[test]
    fn sequence_numbers_wrap_around() {
        let mut jb = JitterBuffer::default();
        for s in [65534, 65535, 0, 1] {
            jb.push(p(s));
        }
        let order: Vec<Option<u16>> = (0..4).map(|_| seq_of(jb.pop())).collect();
        assert_eq!(order, vec![Some(65534), Some(65535), Some(0), Some(1)]);
    }

    #[test]
    fn the_delay_shrinks_after_a_calm_stretch_but_not_below_one_frame() {
        let mut jb = JitterBuffer::default();
        jb.stats.delay = MAX_DELAY;
        let mut seq = 0u16;
        for _ in 0..(CALM_FRAMES * 8) {
            jb.push(p(seq));
            seq = seq.wrapping_add(1);
            jb.pop();
        }
        assert_eq!(jb.stats().delay, 1);
    }

    #[test]
    fn a_sender_that_starts_over_far_away_resets_the_buffer() {
        let mut jb = JitterBuffer::default();
        for s in 0..3 {
            jb.push(p(s));
        }
        jb.pop();
        jb.push(p(5000));
        jb.push(p(5001));
        jb.push(p(5002));
        assert_eq!(seq_of(jb.pop()), Some(5000));
    }

    #[test]
    fn oversized_or_empty_packets_are_refused() {
        assert!(Packet::new(0, false, &[]).is_none());
        assert!(Packet::new(0, false, &[0; MAX_VOICE_BYTES + 1]).is_none());
        assert_eq!(Packet::new(0, false, &[9; 5]).expect("packet").opus(), &[9; 5]);
    }
}
