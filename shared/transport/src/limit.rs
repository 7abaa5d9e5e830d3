//! Token buckets: a rate with a burst, stepped by the caller's clock (seconds as `f64`).

use std::collections::HashMap;
use std::hash::Hash;
use std::net::{IpAddr, Ipv6Addr};

/// The key a source address is limited by: the IPv4 address, or the IPv6 /64 (one host gets a whole /64).
pub fn address_key(ip: IpAddr) -> IpAddr {
    match ip {
        IpAddr::V4(_) => ip,
        IpAddr::V6(v6) => match v6.to_ipv4_mapped() {
            Some(v4) => IpAddr::V4(v4),
            None => IpAddr::V6(Ipv6Addr::from(u128::from(v6) & !((1u128 << 64) - 1))),
        },
    }
}

/// A rate limit: `burst` at once, refilled at `per_s` a second.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rate {
    /// Tokens refilled per second.
    pub per_s: f64,
    /// Bucket size: how many may come at once.
    pub burst: f64,
}

impl Rate {
    /// `per_s` a second, `burst` at once.
    pub const fn new(per_s: f64, burst: f64) -> Self {
        Self { per_s, burst }
    }
}

/// One bucket.
#[derive(Clone, Copy, Debug)]
pub struct Bucket {
    tokens: f64,
    at_s: f64,
}

impl Bucket {
    /// A full bucket at `now_s`.
    pub fn full(rate: Rate, now_s: f64) -> Self {
        Self { tokens: rate.burst, at_s: now_s }
    }

    /// Takes one token if there is one.
    pub fn take(&mut self, rate: Rate, now_s: f64) -> bool {
        self.refill(rate, now_s);
        if self.tokens >= 1.0 {
            self.tokens -= 1.0;
            true
        } else {
            false
        }
    }

    /// Gives back a token taken for something that did not happen.
    pub fn refund(&mut self, rate: Rate) {
        self.tokens = (self.tokens + 1.0).min(rate.burst);
    }

    /// True when the bucket has refilled completely (it can be forgotten).
    pub fn is_full(&self, rate: Rate, now_s: f64) -> bool {
        self.tokens + (now_s - self.at_s).max(0.0) * rate.per_s >= rate.burst
    }

    fn refill(&mut self, rate: Rate, now_s: f64) {
        let dt = (now_s - self.at_s).max(0.0);
        self.tokens = (self.tokens + dt * rate.per_s).min(rate.burst);
        self.at_s = self.at_s.max(now_s);
    }
}

/// A bucket per key (an address), plus one bucket for all keys together; at most `max_keys` keys are
/// tracked (full buckets are forgotten first), so memory stays bounded whoever sends.
#[derive(Debug)]
pub struct KeyedLimiter<K> {
    each: Rate,
    all: Rate,
    total: Bucket,
    buckets: HashMap<K, Bucket>,
    max_keys: usize,
}

impl<K: Eq + Hash + Copy> KeyedLimiter<K> {
    /// `each` per key, `all` for every key together, at most `max_keys` keys remembered.
    pub fn new(each: Rate, all: Rate, max_keys: usize) -> Self {
        Self { each, all, total: Bucket::full(all, 0.0), buckets: HashMap::new(), max_keys }
    }

    /// Takes a token for `key` and one from the shared bucket; false when either is empty.
    pub fn take(&mut self, key: K, now_s: f64) -> bool {
        if !self.buckets.contains_key(&key) && self.buckets.len() >= self.max_keys {
            let (each, max) = (self.each, self.max_keys);
            self.buckets.retain(|_, b| !b.is_full(each, now_s));
            if self.buckets.len() >= max {
                // Every tracked key is busy: a new one shares the total bucket only.
                return self.total.take(self.all, now_s);
            }
        }
        let each = self.each;
        let bucket = self.buckets.entry(key).or_insert_with(|| Bucket::full(each, now_s));
        bucket.take(each, now_s) && self.total.take(self.all, now_s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bucket_gives_its_burst_then_its_rate() {
        let rate = Rate::new(2.0, 3.0);
        let mut b = Bucket::full(rate, 0.0);
        assert_eq!((0..5).filter(|_| b.take(rate, 0.0)).count(), 3);
        assert!(!b.take(rate, 0.25));
        assert!(b.take(rate, 0.5));
        assert!(!b.take(rate, 0.5));
    }

    #[test]
    fn each_key_has_its_own_bucket_and_all_share_one() {
        let mut l = KeyedLimiter::new(Rate::new(1.0, 2.0), Rate::new(1.0, 3.0), 8);
        assert!(l.take(1, 0.0) && l.take(1, 0.0));
        assert!(!l.take(1, 0.0), "key 1 spent its burst");
        assert!(l.take(2, 0.0));
        assert!(!l.take(3, 0.0), "the shared bucket is spent");
    }

    #[test]
    fn an_ipv6_host_is_one_key_for_its_whole_64() {
        let a: IpAddr = "2001:db8:1:2:aaaa::1".parse().unwrap();
        let b: IpAddr = "2001:db8:1:2:ffff::9".parse().unwrap();
        let c: IpAddr = "2001:db8:1:3::1".parse().unwrap();
        assert_eq!(address_key(a), address_key(b));
        assert_ne!(address_key(a), address_key(c));
        let mapped: IpAddr = "::ffff:10.0.0.1".parse().unwrap();
        assert_eq!(address_key(mapped), "10.0.0.1".parse::<IpAddr>().unwrap());
    }

    #[test]
    fn the_number_of_keys_stays_bounded() {
        let mut l = KeyedLimiter::new(Rate::new(1.0, 1.0), Rate::new(1e9, 1e9), 4);
        for k in 0..1000 {
            l.take(k, 0.0);
        }
        assert!(l.buckets.len() <= 4);
    }
}
