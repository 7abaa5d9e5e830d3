//! The light delegate system (paper §3.2): a [`Delegator`] is an event, delegates are the callables
//! bound to it, and `broadcast` calls them one after another with a reference to the event's data.
//!
//! You need this module when you hook your own code into the haptic or collision thread (for example a
//! force function on `ForceOnHapticTick`) or when you wire the three haptic crates together.
//!
//! # Threads
//! A `Delegator` is owned by exactly one thread at a time (it is `Send`, not `Sync`):
//! - **binding** (`add_delegate`, `add_fn`, `add_method`) allocates one box per delegate, so do it on a
//!   setup or game thread, before the delegator is moved into the real-time thread, or send the boxed
//!   delegate there as a command and bind it with [`Delegator::bind_boxed`] (which does not allocate while
//!   the capacity given to [`Delegator::with_capacity`] lasts);
//! - **unbinding** through a [`DelegateHandle`] is an atomic store and may happen on any thread at any time,
//!   even from inside a delegate during a broadcast; delegates not yet called in that broadcast are skipped;
//! - **broadcasting** is done by the owning thread; it takes no lock and does not allocate;
//! - **purging** unbound delegates ([`Delegator::purge_unbound`]) hands their boxes to a sink of your choice,
//!   so a real-time thread can pass them back to a thread that is allowed to free memory.
//!
//! # Reentrancy
//! `broadcast` borrows the delegator mutably, so a delegate can never bind to, purge or broadcast the
//! delegator that is calling it: the compiler refuses it. A delegate may broadcast *other* delegators it owns
//! or captures, and may unbind any delegate (including itself) through a handle.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// A boxed delegate for events of type `T`.
pub type BoxedDelegate<T> = Box<dyn FnMut(&T) + Send>;

/// Unbinds its delegate when asked; cheap to clone, usable from any thread. Dropping it does *not* unbind.
#[derive(Clone, Debug)]
pub struct DelegateHandle {
    id: u64,
    bound: Arc<AtomicBool>,
}

impl DelegateHandle {
    /// Unbinds the delegate: it is never called again, starting with the broadcast in progress (if any).
    pub fn unbind(&self) {
        self.bound.store(false, Ordering::Release);
    }

    /// True while the delegate is bound.
    pub fn is_bound(&self) -> bool {
        self.bound.load(Ordering::Acquire)
    }

    /// Identifier of the delegate, unique within its delegator.
    pub fn id(&self) -> u64 {
        self.id
    }
}

/// A delegate prepared on one thread to be bound on another (see [`Delegator::bind_boxed`]).
pub struct PendingDelegate<T: ?Sized> {
    slot: Slot<T>,
}

impl<T: ?Sized> PendingDelegate<T> {
    /// Boxes `delegate` (allocates: call off the real-time thread) and returns it with its handle.
    pub fn new(delegate: impl FnMut(&T) + Send + 'static) -> (Self, DelegateHandle) {
        // Ids of pending delegates come from a process-wide counter so they never clash with local ones.
        static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1 << 63);
        let id = NEXT.fetch_add(1, Ordering::Relaxed);
        let bound = Arc::new(AtomicBool::new(true));
        let handle = DelegateHandle { id, bound: bound.clone() };
        (Self { slot: Slot { id, bound, delegate: Box::new(delegate) } }, handle)
    }
}

struct Slot<T: ?Sized> {
    id: u64,
    bound: Arc<AtomicBool>,
    delegate: Box<dyn FnMut(&T) + Send>,
}

/// An event: a list of delegates called in the order they were bound, each with `&T`.
pub struct Delegator<T: ?Sized> {
    slots: Vec<Slot<T>>,
    next_id: u64,
}

impl<T: ?Sized + 'static> Default for Delegator<T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: ?Sized> std::fmt::Debug for Delegator<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Delegator").field("delegates", &self.slots.len()).finish()
    }
}

impl<T: ?Sized + 'static> Delegator<T> {
    /// An event with no delegates and no reserved capacity.
    pub fn new() -> Self {
        Self { slots: Vec::new(), next_id: 0 }
    }

    /// An event with room for `capacity` delegates, so `bind_boxed` does not allocate up to that count.
    pub fn with_capacity(capacity: usize) -> Self {
        Self { slots: Vec::with_capacity(capacity), next_id: 0 }
    }

    /// Binds a closure (or any `FnMut(&T)`); returns the handle that unbinds it. Allocates.
    pub fn add_delegate(&mut self, delegate: impl FnMut(&T) + Send + 'static) -> DelegateHandle {
        let id = self.next_id;
        self.next_id += 1;
        let bound = Arc::new(AtomicBool::new(true));
        self.slots.push(Slot { id, bound: bound.clone(), delegate: Box::new(delegate) });
        DelegateHandle { id, bound }
    }

    /// Binds a free function. Allocates.
    pub fn add_fn(&mut self, function: fn(&T)) -> DelegateHandle {
        self.add_delegate(function)
    }

    /// Binds a method: `method(&mut receiver, event)`; the receiver moves into the delegate. Allocates.
    pub fn add_method<R: Send + 'static>(&mut self, mut receiver: R, method: fn(&mut R, &T)) -> DelegateHandle {
        self.add_delegate(move |event: &T| method(&mut receiver, event))
    }

    /// Reserves room for `additional` more delegates (allocates: call before the real-time thread starts).
    pub fn reserve(&mut self, additional: usize) {
        self.slots.reserve(additional);
    }

    /// Binds a delegate boxed elsewhere; allocation-free while the reserved capacity lasts.
    /// Returns the delegate back when the capacity is exhausted, so the caller can free it off-thread.
    pub fn bind_boxed(&mut self, pending: PendingDelegate<T>) -> Result<(), PendingDelegate<T>> {
        if self.slots.len() == self.slots.capacity() {
            return Err(pending);
        }
        self.slots.push(pending.slot);
        Ok(())
    }

    /// Calls every bound delegate, in binding order, with `event`. No lock, no allocation.
    pub fn broadcast(&mut self, event: &T) {
        for slot in &mut self.slots {
            if slot.bound.load(Ordering::Acquire) {
                (slot.delegate)(event);
            }
        }
    }

    /// Number of delegates held, bound or not yet purged.
    pub fn len(&self) -> usize {
        self.slots.len()
    }

    /// True when no delegate is held.
    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }

    /// Number of delegates still bound.
    pub fn bound_count(&self) -> usize {
        self.slots.iter().filter(|s| s.bound.load(Ordering::Acquire)).count()
    }

    /// Removes unbound delegates, keeping order, and gives each removed box to `sink` (which decides where
    /// it is freed). Does not allocate.
    pub fn purge_unbound(&mut self, mut sink: impl FnMut(BoxedDelegate<T>)) {
        let mut i = 0;
        while i < self.slots.len() {
            if self.slots[i].bound.load(Ordering::Acquire) {
                i += 1;
            } else {
                let slot = self.slots.remove(i);
                sink(slot.delegate);
            }
        }
    }

    /// True when the delegate of `handle` is held by this delegator.
    pub fn contains(&self, handle: &DelegateHandle) -> bool {
        self.slots.iter().any(|s| s.id == handle.id && Arc::ptr_eq(&s.bound, &handle.bound))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    type Log = Arc<Mutex<Vec<u32>>>;

    fn recorder() -> (Log, impl Fn(u32) -> BoxedDelegate<u32>) {
        let log = Arc::new(Mutex::new(Vec::new()));
        let l = log.clone();
        let make = move |tag: u32| -> BoxedDelegate<u32> {
            let l = l.clone();
            Box::new(move |v: &u32| l.lock().expect("test lock").push(tag * 100 + v))
        };
        (log, make)
    }

    #[test]
    fn broadcast_calls_delegates_in_binding_order() {
        let (log, make) = recorder();
        let mut d = Delegator::<u32>::new();
        d.add_delegate(make(1));
        d.add_delegate(make(2));
        d.add_delegate(make(3));
        d.broadcast(&7);
        assert_eq!(*log.lock().expect("lock"), vec![107, 207, 307]);
    }

    #[test]
    fn an_unbound_delegate_is_never_called_again() {
        let (log, make) = recorder();
        let mut d = Delegator::<u32>::new();
        let h1 = d.add_delegate(make(1));
        d.add_delegate(make(2));
        h1.unbind();
        assert!(!h1.is_bound());
        d.broadcast(&1);
        assert_eq!(*log.lock().expect("lock"), vec![201]);
        assert_eq!(d.bound_count(), 1);
        let mut purged = 0;
        d.purge_unbound(|_| purged += 1);
        assert_eq!((purged, d.len()), (1, 1));
    }

    #[test]
    fn a_delegate_may_unbind_a_later_one_during_a_broadcast() {
        let (log, make) = recorder();
        let mut d = Delegator::<u32>::new();
        let later: Arc<Mutex<Option<DelegateHandle>>> = Arc::new(Mutex::new(None));
        let later2 = later.clone();
        d.add_delegate(move |_: &u32| {
            if let Some(h) = later2.lock().expect("lock").as_ref() {
                h.unbind();
            }
        });
        let h = d.add_delegate(make(2));
        *later.lock().expect("lock") = Some(h);
        d.broadcast(&0);
        assert!(log.lock().expect("lock").is_empty());
    }

    #[test]
    fn a_delegate_may_unbind_itself_and_broadcast_another_delegator() {
        let (log, make) = recorder();
        let mut inner = Delegator::<u32>::new();
        inner.add_delegate(make(9));
        let mut outer = Delegator::<u32>::new();
        let me: Arc<Mutex<Option<DelegateHandle>>> = Arc::new(Mutex::new(None));
        let me2 = me.clone();
        let h = outer.add_delegate(move |v: &u32| {
            inner.broadcast(v);
            if let Some(h) = me2.lock().expect("lock").as_ref() {
                h.unbind();
            }
        });
        *me.lock().expect("lock") = Some(h);
        outer.broadcast(&1);
        outer.broadcast(&2);
        assert_eq!(*log.lock().expect("lock"), vec![901]);
    }

    #[test]
    fn free_functions_and_methods_can_be_bound() {
        static HITS: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
        fn free(v: &u32) {
            HITS.fetch_add(*v, Ordering::Relaxed);
        }
        struct Counter(Arc<std::sync::atomic::AtomicU32>);
        impl Counter {
            fn on_event(&mut self, v: &u32) {
                self.0.fetch_add(*v * 10, Ordering::Relaxed);
            }
        }
        let total = Arc::new(std::sync::atomic::AtomicU32::new(0));
        let mut d = Delegator::<u32>::new();
        d.add_fn(free);
        d.add_method(Counter(total.clone()), Counter::on_event);
        d.broadcast(&3);
        assert_eq!(HITS.load(Ordering::Relaxed), 3);
        assert_eq!(total.load(Ordering::Relaxed), 30);
    }

    #[test]
    fn bind_boxed_refuses_past_capacity_instead_of_allocating() {
        let mut d = Delegator::<u32>::with_capacity(1);
        let (p1, h1) = PendingDelegate::new(|_: &u32| {});
        let (p2, _h2) = PendingDelegate::new(|_: &u32| {});
        assert!(d.bind_boxed(p1).is_ok());
        assert!(d.bind_boxed(p2).is_err());
        assert!(d.contains(&h1));
    }

    #[test]
    fn unsized_events_can_be_broadcast() {
        let mut d = Delegator::<[f32]>::new();
        let sum = Arc::new(Mutex::new(0.0));
        let s = sum.clone();
        d.add_delegate(move |v: &[f32]| *s.lock().expect("lock") += v.iter().sum::<f32>());
        d.broadcast(&[1.0, 2.0][..]);
        assert_eq!(*sum.lock().expect("lock"), 3.0);
    }
}
