//! The token endpoint's open connections, capped per address and in total. At a cap the oldest
//! connection gives way: idle or slow connections can never keep a newcomer out.

use std::collections::{BTreeMap, HashMap, VecDeque};
use std::net::IpAddr;

/// Open connections by id (ids grow, so the first is the oldest), each with a handle to end it.
#[derive(Debug)]
pub struct Connections<H> {
    next: u64,
    open: BTreeMap<u64, (IpAddr, H)>,
    per_key: HashMap<IpAddr, VecDeque<u64>>,
    per_key_max: usize,
    total_max: usize,
}

impl<H> Connections<H> {
    /// At most `per_key_max` connections per address key, `total_max` in all.
    pub fn new(per_key_max: usize, total_max: usize) -> Self {
        Self { next: 0, open: BTreeMap::new(), per_key: HashMap::new(), per_key_max, total_max }
    }

    /// The id the next connection gets.
    pub fn next_id(&mut self) -> u64 {
        self.next += 1;
        self.next
    }

    /// Registers connection `id` from `key`; returns the handles of the connections it pushed out.
    pub fn open(&mut self, id: u64, key: IpAddr, handle: H) -> Vec<H> {
        let mut out = Vec::new();
        let mine = self.per_key.get(&key).map_or(0, VecDeque::len);
        if mine >= self.per_key_max
            && let Some(oldest) = self.per_key.get(&key).and_then(|q| q.front().copied())
            && let Some(h) = self.close(oldest)
        {
            out.push(h);
        }
        if self.open.len() >= self.total_max
            && let Some(oldest) = self.open.keys().next().copied()
            && let Some(h) = self.close(oldest)
        {
            out.push(h);
        }
        self.open.insert(id, (key, handle));
        self.per_key.entry(key).or_default().push_back(id);
        out
    }

    /// Forgets connection `id` (ended or pushed out); returns its handle if it was open.
    pub fn close(&mut self, id: u64) -> Option<H> {
        let (key, handle) = self.open.remove(&id)?;
        if let Some(q) = self.per_key.get_mut(&key) {
            q.retain(|&i| i != id);
            if q.is_empty() {
                self.per_key.remove(&key);
            }
        }
        Some(handle)
    }

    /// Connections open now.
    #[cfg(test)]
    fn len(&self) -> usize {
        self.open.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ip(last: u8) -> IpAddr {
        IpAddr::from([10, 0, 0, last])
    }

    #[test]
    fn the_oldest_connection_of_a_busy_address_gives_way() {
        let mut c = Connections::new(2, 100);
        for n in 1..=2 {
            let id = c.next_id();
            assert!(c.open(id, ip(1), n).is_empty());
        }
        let id = c.next_id();
        assert_eq!(c.open(id, ip(1), 3), vec![1]);
        let id = c.next_id();
        assert!(c.open(id, ip(2), 4).is_empty(), "another address has its own share");
        assert_eq!(c.len(), 3);
    }

    #[test]
    fn the_oldest_connection_of_all_gives_way_at_the_total_cap() {
        let mut c = Connections::new(10, 3);
        for n in 1..=3u8 {
            let id = c.next_id();
            c.open(id, ip(n), n);
        }
        let id = c.next_id();
        assert_eq!(c.open(id, ip(9), 9), vec![1]);
        assert_eq!(c.close(2), Some(2));
        assert_eq!(c.close(2), None, "closing twice is harmless");
        assert_eq!(c.len(), 2);
    }
}
