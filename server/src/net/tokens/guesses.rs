//! How many join codes an address (and everyone together) may get wrong: a few at once, then answers slow
//! down, then the address is refused for a while, longer each time.
//!
//! Pure bookkeeping over the caller's clock (seconds as `f64`), so every rule is tested without sockets.

use std::collections::HashMap;
use std::net::IpAddr;

use heist_shared::protocol::join::JoinRefusal;
use heist_transport::limit::{Bucket, Rate};

/// The numbers of the wrong-code limit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GuessLimits {
    /// Wrong codes from one address answered at once; default 3.
    pub free: u32,
    /// Wrong codes from one address before it is refused; default 5 (the 4th and 5th are answered late).
    pub max: u32,
    /// Delay of the first slowed answer, seconds, doubling after; default 0.5.
    pub first_delay_s: f64,
    /// First refusal period, seconds, doubling with each; default 60.
    pub lockout_s: f64,
    /// Longest refusal period, seconds; default 3600.
    pub max_lockout_s: f64,
    /// An address's wrong codes are forgotten this long after its last one, seconds; default 900.
    pub forget_s: f64,
    /// Wrong codes from all addresses together; default 1 a second, 30 at once.
    pub global: Rate,
    /// Addresses remembered at once; default 16384.
    pub tracked: usize,
}

impl Default for GuessLimits {
    fn default() -> Self {
        Self {
            free: 3,
            max: 5,
            first_delay_s: 0.5,
            lockout_s: 60.0,
            max_lockout_s: 3600.0,
            forget_s: 900.0,
            global: Rate::new(1.0, 30.0),
            tracked: 16384,
        }
    }
}

/// One address's record.
#[derive(Clone, Copy, Debug, Default)]
struct Record {
    wrong: u32,
    in_flight: u32,
    lockouts: u32,
    locked_until_s: f64,
    last_s: f64,
}

/// How an attempt ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// The code was right.
    Right,
    /// The code was wrong.
    Wrong,
    /// The client left before it proved anything: no guess was made.
    Abandoned,
}

/// What an ended attempt means for the answer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Verdict {
    /// Seconds to wait before answering.
    pub delay_s: f64,
    /// This wrong code locked the address out, for that many seconds.
    pub locked_for_s: Option<f64>,
}

/// The wrong-code bookkeeping of one endpoint.
#[derive(Debug)]
pub struct Guesses {
    limits: GuessLimits,
    records: HashMap<IpAddr, Record>,
    global: Bucket,
}

impl Guesses {
    /// Nothing recorded yet.
    pub fn new(limits: GuessLimits) -> Self {
        Self { limits, records: HashMap::new(), global: Bucket::full(limits.global, 0.0) }
    }

    /// An attempt from `key` starts; counted as a guess in flight (parallel attempts cannot slip past the
    /// limit) until [`Guesses::end`].
    pub fn begin(&mut self, key: IpAddr, now_s: f64) -> Result<(), JoinRefusal> {
        self.forget_old(now_s);
        let limits = self.limits;
        let mut record = self.records.get(&key).copied().unwrap_or_default();
        if record.locked_until_s > now_s {
            return Err(JoinRefusal::TooManyWrongCodes {
                retry_after_s: (record.locked_until_s - now_s).ceil() as u32,
            });
        }
        if record.locked_until_s > 0.0 {
            // The refusal period is over: a fresh count, but the next period will be twice as long.
            record.wrong = 0;
            record.locked_until_s = 0.0;
        }
        if record.wrong + record.in_flight >= limits.max {
            return Err(JoinRefusal::TooManyWrongCodes { retry_after_s: 1 });
        }
        if !self.global.take(limits.global, now_s) {
            return Err(JoinRefusal::Busy { retry_after_s: (1.0 / limits.global.per_s).ceil() as u32 });
        }
        record.in_flight += 1;
        record.last_s = now_s;
        self.records.insert(key, record);
        Ok(())
    }

    /// The attempt from `key` ended with `outcome`.
    pub fn end(&mut self, key: IpAddr, outcome: Outcome, now_s: f64) -> Verdict {
        let limits = self.limits;
        if outcome != Outcome::Wrong {
            self.global.refund(limits.global);
        }
        let Some(record) = self.records.get_mut(&key) else { return Verdict { delay_s: 0.0, locked_for_s: None } };
        record.in_flight = record.in_flight.saturating_sub(1);
        record.last_s = now_s;
        if outcome != Outcome::Wrong {
            return Verdict { delay_s: 0.0, locked_for_s: None };
        }
        record.wrong += 1;
        let slowed = record.wrong.saturating_sub(limits.free);
        let delay_s = if slowed == 0 { 0.0 } else { limits.first_delay_s * 2f64.powi(slowed as i32 - 1) };
        let mut locked_for_s = None;
        if record.wrong >= limits.max {
            let period = (limits.lockout_s * 2f64.powi(record.lockouts as i32)).min(limits.max_lockout_s);
            record.lockouts += 1;
            record.locked_until_s = now_s + period;
            locked_for_s = Some(period);
        }
        Verdict { delay_s, locked_for_s }
    }

    /// Drops records that say nothing any more; when there are still too many, the stalest ones.
    fn forget_old(&mut self, now_s: f64) {
        if self.records.len() < self.limits.tracked {
            return;
        }
        let forget_s = self.limits.forget_s;
        self.records.retain(|_, r| r.in_flight > 0 || r.locked_until_s > now_s || now_s - r.last_s < forget_s);
        while self.records.len() >= self.limits.tracked {
            let Some(stalest) = self.records.iter().min_by(|a, b| a.1.last_s.total_cmp(&b.1.last_s)).map(|(k, _)| *k)
            else {
                break;
            };
            self.records.remove(&stalest);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ip(last: u8) -> IpAddr {
        IpAddr::from([10, 0, 0, last])
    }

    fn wrong(g: &mut Guesses, key: IpAddr, now_s: f64) -> Result<Verdict, JoinRefusal> {
        g.begin(key, now_s)?;
        Ok(g.end(key, Outcome::Wrong, now_s))
    }

    #[test]
    fn three_wrong_codes_are_free_two_more_are_slowed_the_sixth_is_refused() {
        let mut g = Guesses::new(GuessLimits::default());
        let delays: Vec<f64> = (0..5).map(|_| wrong(&mut g, ip(1), 0.0).unwrap().delay_s).collect();
        assert_eq!(delays, [0.0, 0.0, 0.0, 0.5, 1.0]);
        assert_eq!(wrong(&mut g, ip(1), 1.0), Err(JoinRefusal::TooManyWrongCodes { retry_after_s: 59 }));
        assert!(g.begin(ip(2), 1.0).is_ok(), "another address is not affected");
    }

    #[test]
    fn each_lockout_is_twice_as_long_as_the_last() {
        let mut g = Guesses::new(GuessLimits::default());
        let mut now = 0.0;
        let mut periods = Vec::new();
        for _ in 0..3 {
            for _ in 0..5 {
                if let Some(p) = wrong(&mut g, ip(1), now).unwrap().locked_for_s {
                    periods.push(p);
                    now += p + 0.1;
                }
            }
        }
        assert_eq!(periods, [60.0, 120.0, 240.0]);
    }

    #[test]
    fn guesses_in_flight_count_so_parallel_attempts_cannot_slip_through() {
        let mut g = Guesses::new(GuessLimits::default());
        for _ in 0..5 {
            g.begin(ip(1), 0.0).unwrap();
        }
        assert!(matches!(g.begin(ip(1), 0.0), Err(JoinRefusal::TooManyWrongCodes { .. })));
        g.end(ip(1), Outcome::Abandoned, 0.0);
        assert!(g.begin(ip(1), 0.0).is_ok(), "an abandoned attempt made no guess");
    }

    #[test]
    fn a_right_code_costs_nothing_and_the_whole_server_has_a_budget() {
        let limits = GuessLimits { global: Rate::new(1.0, 3.0), ..GuessLimits::default() };
        let mut g = Guesses::new(limits);
        for last in 0..3 {
            wrong(&mut g, ip(last), 0.0).unwrap();
        }
        assert_eq!(wrong(&mut g, ip(9), 0.0), Err(JoinRefusal::Busy { retry_after_s: 1 }));
        assert!(wrong(&mut g, ip(9), 1.0).is_ok(), "the budget refills");
        g.begin(ip(10), 2.0).unwrap();
        g.end(ip(10), Outcome::Right, 2.0);
        assert!(g.begin(ip(11), 2.0).is_ok(), "a right code gave its token back");
    }

    #[test]
    fn memory_stays_bounded_whoever_tries() {
        let limits = GuessLimits { tracked: 64, global: Rate::new(1e9, 1e9), ..GuessLimits::default() };
        let mut g = Guesses::new(limits);
        for i in 0..10_000u32 {
            let key = IpAddr::from(i.to_be_bytes());
            let _ = wrong(&mut g, key, f64::from(i));
        }
        assert!(g.records.len() <= 64);
    }
}
