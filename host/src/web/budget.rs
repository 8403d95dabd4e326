//! The connection budget: every open connection counted, in total and per
//! client address (each address its own client, loopback ones included).
//! A connection that has not yet sent its request head is *pending*; when
//! the budget is full a new one evicts the oldest pending connection of
//! the client holding the most, so idle sockets can never lock anyone out.
//! Once its head is in, a connection serves one request: page and API
//! requests may fill the budget but for a reserve only control requests
//! use, and event streams have their own caps, so the Stop button always
//! finds a slot.

use std::collections::HashMap;
use std::net::IpAddr;
use std::time::Instant;

use tokio::sync::oneshot;

/// How many connections of which kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// Open connections at most.
    pub total: usize,
    /// Open connections of one client address at most.
    pub per_client: usize,
    /// Slots only control requests may serve in.
    pub control_reserve: usize,
    /// Event streams at most, and per client address.
    pub streams: usize,
    pub streams_per_client: usize,
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            total: 128,
            per_client: 32,
            control_reserve: 16,
            streams: 32,
            streams_per_client: 8,
        }
    }
}

/// What a connection is doing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Accepted, no complete request head yet.
    Pending,
    /// Serving a page or API request.
    Request,
    /// Serving an event stream.
    Stream,
    /// Serving a control request (hold, resume, stop).
    Control,
}

/// Why a request is not served now.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Busy {
    /// Every slot outside the control reserve serves a request.
    Requests,
    /// The event-stream caps (total, or this client's).
    Streams,
}

#[derive(Debug)]
struct Conn {
    client: IpAddr,
    since: Instant,
    kind: Kind,
    /// Dropping it closes the connection (eviction).
    _evict: oneshot::Sender<()>,
}

/// The open connections.
#[derive(Debug, Default)]
pub struct Budget {
    limits: Limits,
    conns: HashMap<u64, Conn>,
    next: u64,
    /// Pending connections evicted and new ones refused, since start.
    pub evicted: u64,
    pub refused: u64,
}

/// The client address: an IPv4-mapped IPv6 address is its IPv4 address.
pub fn client(ip: IpAddr) -> IpAddr {
    ip.to_canonical()
}

impl Budget {
    pub fn new(limits: Limits) -> Self {
        Self {
            limits,
            ..Self::default()
        }
    }

    fn count(&self, f: impl Fn(&Conn) -> bool) -> usize {
        self.conns.values().filter(|c| f(c)).count()
    }

    /// The oldest pending connection among those `f` picks.
    fn oldest_pending(&self, f: impl Fn(&Conn) -> bool) -> Option<u64> {
        self.conns
            .iter()
            .filter(|(_, c)| c.kind == Kind::Pending && f(c))
            .min_by_key(|(id, c)| (c.since, **id))
            .map(|(id, _)| *id)
    }

    /// The oldest pending connection of the client with the most open
    /// (ties: the oldest of them).
    fn victim(&self) -> Option<u64> {
        let mut per: HashMap<IpAddr, usize> = HashMap::new();
        for c in self.conns.values() {
            *per.entry(c.client).or_default() += 1;
        }
        self.conns
            .iter()
            .filter(|(_, c)| c.kind == Kind::Pending)
            .max_by_key(|(id, c)| {
                (
                    per[&c.client],
                    std::cmp::Reverse(c.since),
                    std::cmp::Reverse(**id),
                )
            })
            .map(|(id, _)| *id)
    }

    /// A new connection from `ip` at `now`: its id and what closes it, or
    /// `None` (refused: every slot it could take is serving a request).
    pub fn admit(&mut self, ip: IpAddr, now: Instant) -> Option<(u64, oneshot::Receiver<()>)> {
        let ip = client(ip);
        let evict = if self.count(|c| c.client == ip) >= self.limits.per_client {
            Some(self.oldest_pending(|c| c.client == ip))
        } else if self.conns.len() >= self.limits.total {
            Some(self.victim())
        } else {
            None
        };
        match evict {
            Some(Some(id)) => {
                self.conns.remove(&id);
                self.evicted += 1;
            }
            Some(None) => {
                self.refused += 1;
                return None;
            }
            None => {}
        }
        let (tx, rx) = oneshot::channel();
        self.next += 1;
        self.conns.insert(
            self.next,
            Conn {
                client: ip,
                since: now,
                kind: Kind::Pending,
                _evict: tx,
            },
        );
        Some((self.next, rx))
    }

    /// Connection `id` read its request head: may it serve it as `kind`?
    pub fn serve(&mut self, id: u64, kind: Kind) -> Result<(), Busy> {
        let Some(ip) = self.conns.get(&id).map(|c| c.client) else {
            // Evicted meanwhile: it is closing anyway.
            return Err(Busy::Requests);
        };
        let serving = self.count(|c| matches!(c.kind, Kind::Request | Kind::Stream));
        let l = self.limits;
        match kind {
            Kind::Pending | Kind::Control => {}
            _ if serving >= l.total.saturating_sub(l.control_reserve) => {
                return Err(Busy::Requests);
            }
            Kind::Stream
                if self.count(|c| c.kind == Kind::Stream) >= l.streams
                    || self.count(|c| c.kind == Kind::Stream && c.client == ip)
                        >= l.streams_per_client =>
            {
                return Err(Busy::Streams);
            }
            Kind::Request | Kind::Stream => {}
        }
        if let Some(c) = self.conns.get_mut(&id) {
            c.kind = kind;
        }
        Ok(())
    }

    /// Connection `id` closed.
    pub fn release(&mut self, id: u64) {
        self.conns.remove(&id);
    }

    /// Open connections.
    pub fn open(&self) -> usize {
        self.conns.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    fn ip(last: u8) -> IpAddr {
        IpAddr::from([127, 0, 0, last])
    }

    fn small() -> Limits {
        Limits {
            total: 6,
            per_client: 4,
            control_reserve: 2,
            streams: 3,
            streams_per_client: 2,
        }
    }

    #[test]
    fn a_full_budget_evicts_the_oldest_pending_of_the_biggest_client() {
        let mut b = Budget::new(small());
        let t = Instant::now();
        let at = |ms| t + Duration::from_millis(ms);
        let mut rx = Vec::new();
        // Client .2 holds 4 (its cap), client .3 holds 2: the budget is full.
        for k in 0..4 {
            rx.push(b.admit(ip(2), at(k)).unwrap());
        }
        for k in 4..6 {
            rx.push(b.admit(ip(3), at(k)).unwrap());
        }
        assert_eq!(b.open(), 6);
        // A fifth from .2: its own oldest pending goes.
        let _e = b.admit(ip(2), at(10)).unwrap();
        assert!(
            rx[0]
                .1
                .try_recv()
                .is_err_and(|e| e == oneshot::error::TryRecvError::Closed)
        );
        assert!(
            rx[1]
                .1
                .try_recv()
                .is_err_and(|e| e == oneshot::error::TryRecvError::Empty)
        );
        // A newcomer (.1): the oldest pending of .2, the biggest client.
        let (stop, _) = b.admit(ip(1), at(11)).unwrap();
        assert!(
            rx[1]
                .1
                .try_recv()
                .is_err_and(|e| e == oneshot::error::TryRecvError::Closed)
        );
        assert!(
            rx[4]
                .1
                .try_recv()
                .is_err_and(|e| e == oneshot::error::TryRecvError::Empty)
        );
        assert_eq!(b.open(), 6);
        assert_eq!(b.evicted, 2);
        // Its control request is served even with every other slot busy.
        assert_eq!(b.serve(stop, Kind::Control), Ok(()));
    }

    #[test]
    fn requests_leave_the_reserve_to_control_and_streams_have_caps() {
        let mut b = Budget::new(small());
        let t = Instant::now();
        let ids: Vec<u64> = (0..6)
            .map(|k| b.admit(ip(2 + k / 2), t).unwrap().0)
            .collect();
        // Streams: 2 of one client at most, 3 in all.
        assert_eq!(b.serve(ids[0], Kind::Stream), Ok(()));
        assert_eq!(b.serve(ids[1], Kind::Stream), Ok(()));
        assert_eq!(b.serve(ids[2], Kind::Stream), Ok(()));
        assert_eq!(b.serve(ids[3], Kind::Stream), Err(Busy::Streams));
        // Four serving (total 6 less a reserve of 2): the next request waits.
        assert_eq!(b.serve(ids[3], Kind::Request), Ok(()));
        assert_eq!(b.serve(ids[4], Kind::Request), Err(Busy::Requests));
        assert_eq!(b.serve(ids[4], Kind::Control), Ok(()));
        assert_eq!(b.serve(ids[5], Kind::Control), Ok(()));
        // Nothing pending left: a seventh connection is refused.
        assert!(b.admit(ip(9), t).is_none());
        assert_eq!(b.refused, 1);
        b.release(ids[0]);
        assert!(b.admit(ip(9), t).is_some());
    }

    #[test]
    fn each_loopback_address_is_its_own_client() {
        let mut b = Budget::new(small());
        let t = Instant::now();
        for _ in 0..4 {
            b.admit(ip(2), t).unwrap();
        }
        // .2 is at its cap; .3 is not.
        let (id, _) = b.admit(ip(3), t).unwrap();
        assert_eq!(b.serve(id, Kind::Stream), Ok(()));
        let mapped: IpAddr = "::ffff:127.0.0.3".parse().unwrap();
        assert_eq!(client(mapped), ip(3));
    }
}
