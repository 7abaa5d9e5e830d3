//! How often a client may send each kind of message. Past its rate a message is refused with
//! [`Refusal::RateLimited`] and counts against the sender like any refusal, so a flood ends in a
//! disconnection; nothing it asked for happens.

use heist_shared::protocol::{ClientMsg, PhantomMsg, Refusal, ViveMsg};
use heist_transport::limit::{Bucket, Rate};

/// The kinds of client message, each with its own rate (in [`MsgKind::ALL`]'s order).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MsgKind {
    /// The lobby's messages: `Ready`, `Rematch`, `Leave`.
    Ready,
    /// Vive's `Move`: one per tick.
    Move,
    /// Vive's actions: break, pick up, drop, throw, place.
    Action,
    /// Phantom's verdicts.
    Verdict,
    /// Phantom's tool pose: 20 a second from the client.
    ToolPose,
    /// Phantom's warnings to Vive, and Vive's client's acknowledgements of them.
    Warn,
}

impl MsgKind {
    /// Every kind, in [`MessageLimits`]' order.
    pub const ALL: [MsgKind; 6] =
        [MsgKind::Ready, MsgKind::Move, MsgKind::Action, MsgKind::Verdict, MsgKind::ToolPose, MsgKind::Warn];

    /// The kind of `msg`; `None` for a malformed one (refused anyway).
    pub fn of(msg: &ClientMsg) -> Option<Self> {
        Some(match msg {
            ClientMsg::Lobby(_) => MsgKind::Ready,
            ClientMsg::Vive(ViveMsg::Move { .. }) => MsgKind::Move,
            // As many as Phantom's warnings (the same rate).
            ClientMsg::Vive(ViveMsg::WarningSeen(_)) => MsgKind::Warn,
            ClientMsg::Vive(_) => MsgKind::Action,
            ClientMsg::Phantom(PhantomMsg::Verdict { .. }) => MsgKind::Verdict,
            ClientMsg::Phantom(PhantomMsg::ToolPose { .. }) => MsgKind::ToolPose,
            ClientMsg::Phantom(PhantomMsg::Warn(_)) => MsgKind::Warn,
            ClientMsg::Malformed(_) => return None,
        })
    }

    /// The kind's rate: what an honest client sends, with room for a second or two of bunching.
    pub const fn rate(self) -> Rate {
        match self {
            MsgKind::Ready => Rate::new(2.0, 4.0),
            // 60 a second; a stalled reliable channel may deliver two seconds at once.
            MsgKind::Move => Rate::new(75.0, 120.0),
            MsgKind::Action => Rate::new(10.0, 10.0),
            MsgKind::Verdict => Rate::new(2.0, 4.0),
            MsgKind::ToolPose => Rate::new(120.0, 120.0),
            // A warning is a key a person presses.
            MsgKind::Warn => Rate::new(1.0, 3.0),
        }
    }
}

/// Voice frames: one per 20 ms from an honest client (50 a second), with room for a stall's backlog.
pub const VOICE: Rate = Rate::new(60.0, 30.0);

/// The share of a refusal (one strike) a voice frame over [`VOICE`] counts: a client slightly over
/// the rate loses frames, one flooding is disconnected within seconds.
pub const VOICE_STRIKE: f32 = 0.1;

/// One client's buckets, one per kind, and one for voice frames.
#[derive(Clone, Copy, Debug)]
pub struct MessageLimits {
    kinds: [Bucket; 6],
    voice: Bucket,
}

impl MessageLimits {
    /// Full buckets at `now_s`.
    pub fn new(now_s: f64) -> Self {
        Self { kinds: MsgKind::ALL.map(|k| Bucket::full(k.rate(), now_s)), voice: Bucket::full(VOICE, now_s) }
    }

    /// `Ok` when `msg` is within its kind's rate (it takes a token), else the refusal.
    pub fn check(&mut self, msg: &ClientMsg, now_s: f64) -> Result<(), Refusal> {
        let Some(kind) = MsgKind::of(msg) else { return Ok(()) };
        if self.kinds[kind as usize].take(kind.rate(), now_s) { Ok(()) } else { Err(Refusal::RateLimited) }
    }

    /// True when a voice frame is within [`VOICE`] (it takes a token).
    pub fn check_voice(&mut self, now_s: f64) -> bool {
        self.voice.take(VOICE, now_s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use heist_shared::protocol::WarningKind;

    #[test]
    fn every_kind_has_its_own_bucket_in_declaration_order() {
        for (i, kind) in MsgKind::ALL.into_iter().enumerate() {
            assert_eq!(kind as usize, i);
        }
    }

    #[test]
    fn a_warning_a_second_passes_a_flood_does_not() {
        let mut l = MessageLimits::new(0.0);
        let warn = ClientMsg::Phantom(PhantomMsg::Warn(WarningKind::Hide));
        let passed = (0..100).filter(|_| l.check(&warn, 0.0).is_ok()).count();
        assert_eq!(passed, 3, "the burst");
        assert_eq!(l.check(&warn, 0.5), Err(Refusal::RateLimited));
        assert_eq!(l.check(&warn, 1.0), Ok(()), "one more a second");
    }

    #[test]
    fn kinds_do_not_share_a_budget() {
        let mut l = MessageLimits::new(0.0);
        let warn = ClientMsg::Phantom(PhantomMsg::Warn(WarningKind::Go));
        while l.check(&warn, 0.0).is_ok() {}
        let verdict = ClientMsg::Phantom(PhantomMsg::Verdict { item: heist_shared::protocol::ItemId(0), real: true });
        assert_eq!(l.check(&verdict, 0.0), Ok(()));
    }

    #[test]
    fn a_talking_client_is_never_limited_and_a_voice_flood_is() {
        let mut l = MessageLimits::new(0.0);
        // Fifty frames a second for a minute; now and then half a second's worth arrives at once (a stall).
        for second in 0..60 {
            for i in 0..50 {
                let bunched = f64::from(second) + if i < 25 { 0.0 } else { 0.5 };
                let at = if second % 10 == 9 { bunched } else { f64::from(second) + f64::from(i) * 0.02 };
                assert!(l.check_voice(at), "frame {i} of second {second}");
            }
        }
        let passed = (0..1000).filter(|i| l.check_voice(60.0 + f64::from(*i) * 0.001)).count();
        assert!(passed < 100, "a thousand frames a second: {passed} passed");
        let warn = ClientMsg::Phantom(PhantomMsg::Warn(WarningKind::Go));
        assert_eq!(l.check(&warn, 61.0), Ok(()), "voice has a budget of its own");
    }

    #[test]
    fn an_honest_vive_client_is_never_limited() {
        // One move per tick for a minute, with the whole of each second arriving at once.
        let mut l = MessageLimits::new(0.0);
        let mv =
            ClientMsg::Vive(ViveMsg::Move { seq: 1, direction: glam::Vec2::X, gait: Default::default(), facing: 0.0 });
        for second in 0..60 {
            for _ in 0..60 {
                assert_eq!(l.check(&mv, f64::from(second)), Ok(()));
            }
        }
    }
}
