//! Which requests the server answers: the request target must be a path
//! (an absolute-form target is a proxy request: refused); the Host header
//! must name the address the client connected to, or localhost on a
//! loopback one, with its port (against DNS rebinding); control requests
//! need `--allow-control`, come from loopback unless
//! `--allow-remote-control` (then with the token printed at start), carry
//! no foreign Origin (the scheme, name and port of this server; a missing
//! Origin only from loopback). Hold and resume are rate-limited together;
//! Stop never is.

use std::net::{IpAddr, SocketAddr};
use std::time::{Duration, Instant};

use hyper::StatusCode;
use hyper::header::HeaderMap;

/// A refusal: status and a one-line reason for the body.
pub type Refusal = (StatusCode, String);

/// What the server was started with.
#[derive(Clone, Debug)]
pub struct Policy {
    pub bound: SocketAddr,
    pub allow_control: bool,
    pub allow_remote_control: bool,
    /// Required from remote clients (with `allow_remote_control`).
    pub token: Option<String>,
}

fn refuse(status: StatusCode, why: impl Into<String>) -> Refusal {
    (status, why.into())
}

/// `host[:port]` split, with IPv6 brackets removed.
fn split_host(h: &str) -> Option<(&str, Option<u16>)> {
    let (host, port) = if let Some(rest) = h.strip_prefix('[') {
        let (host, after) = rest.split_once(']')?;
        match after {
            "" => (host, None),
            p => (host, Some(p.strip_prefix(':')?.parse().ok()?)),
        }
    } else {
        match h.rsplit_once(':') {
            Some((host, p)) => (host, Some(p.parse().ok()?)),
            None => (h, None),
        }
    };
    (!host.is_empty()).then_some((host, port))
}

impl Policy {
    /// Does `host` (a Host header, or an Origin's authority) name this
    /// server as reached at `local`? Its name must be `local`'s address,
    /// or localhost when that is a loopback one; its port the bound one
    /// (none: HTTP's 80).
    pub fn names_us(&self, host: &str, local: IpAddr) -> bool {
        let Some((name, port)) = split_host(host) else {
            return false;
        };
        if port.unwrap_or(80) != self.bound.port() {
            return false;
        }
        let local = local.to_canonical();
        let name = name.to_ascii_lowercase();
        if name == "localhost" {
            return local.is_loopback();
        }
        name.parse::<IpAddr>()
            .is_ok_and(|ip| ip.to_canonical() == local)
    }

    /// Every request: a target in origin form (a path), not absolute form
    /// (`GET http://other.example/ HTTP/1.1` asks a proxy).
    pub fn check_target(&self, uri: &hyper::Uri) -> Result<(), Refusal> {
        if uri.scheme().is_some() || uri.authority().is_some() {
            return Err(refuse(
                StatusCode::BAD_REQUEST,
                "absolute-form request target: this server is no proxy",
            ));
        }
        Ok(())
    }

    /// Every request: a Host header that names us.
    pub fn check_host(&self, headers: &HeaderMap, local: IpAddr) -> Result<(), Refusal> {
        let host = headers
            .get(hyper::header::HOST)
            .and_then(|h| h.to_str().ok())
            .ok_or_else(|| refuse(StatusCode::BAD_REQUEST, "no Host header"))?;
        if self.names_us(host, local) {
            Ok(())
        } else {
            Err(refuse(
                StatusCode::MISDIRECTED_REQUEST,
                format!(
                    "Host {host:?} is not this server ({})",
                    SocketAddr::new(local, self.bound.port())
                ),
            ))
        }
    }

    /// A control request from `peer`, received at `local`.
    pub fn check_control(
        &self,
        peer: SocketAddr,
        local: IpAddr,
        headers: &HeaderMap,
    ) -> Result<(), Refusal> {
        if !self.allow_control {
            return Err(refuse(
                StatusCode::FORBIDDEN,
                "control is off: start the monitor with --allow-control",
            ));
        }
        let from_here = peer.ip().to_canonical().is_loopback();
        if !from_here {
            if !self.allow_remote_control {
                return Err(refuse(
                    StatusCode::FORBIDDEN,
                    "control only from this machine (--allow-remote-control allows others)",
                ));
            }
            let given = headers
                .get("x-triquint-token")
                .map(|v| v.as_bytes())
                .unwrap_or_default();
            let ok = self
                .token
                .as_deref()
                .is_some_and(|t| same_secret(t.as_bytes(), given));
            if !ok {
                return Err(refuse(
                    StatusCode::UNAUTHORIZED,
                    "missing or wrong X-Triquint-Token",
                ));
            }
        }
        match headers.get(hyper::header::ORIGIN) {
            None if from_here => Ok(()),
            None => Err(refuse(StatusCode::FORBIDDEN, "no Origin header")),
            Some(o) => {
                let o = o.to_str().unwrap_or("");
                // Only http: this server speaks no TLS.
                let authority = o.strip_prefix("http://").unwrap_or("");
                if self.names_us(authority, local) {
                    Ok(())
                } else {
                    Err(refuse(
                        StatusCode::FORBIDDEN,
                        format!("foreign Origin {o:?}"),
                    ))
                }
            }
        }
    }
}

/// `a == b` in a time that does not depend on where they differ (a token
/// guessed byte by byte over the network).
fn same_secret(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(0u8, |d, (x, y)| d | (x ^ y)) == 0
}

/// At most `burst` control requests at once, refilled at `per_s`.
#[derive(Debug)]
pub struct RateLimit {
    tokens: f64,
    burst: f64,
    per_s: f64,
    last: Instant,
}

impl RateLimit {
    pub fn new(burst: u32, per_s: f64) -> Self {
        Self {
            tokens: f64::from(burst),
            burst: f64::from(burst),
            per_s,
            last: Instant::now(),
        }
    }

    /// Takes one token at `now`, or says how long to wait.
    pub fn take(&mut self, now: Instant) -> Result<(), Duration> {
        let dt = now.saturating_duration_since(self.last).as_secs_f64();
        self.last = now;
        self.tokens = (self.tokens + dt * self.per_s).min(self.burst);
        if self.tokens >= 1.0 {
            self.tokens -= 1.0;
            Ok(())
        } else {
            Err(Duration::from_secs_f64((1.0 - self.tokens) / self.per_s))
        }
    }
}

/// A random token (hex, 128 bits) from the kernel's generator.
pub fn new_token() -> std::io::Result<String> {
    use std::io::Read;
    let mut b = [0u8; 16];
    std::fs::File::open("/dev/urandom")?.read_exact(&mut b)?;
    Ok(b.iter().map(|x| format!("{x:02x}")).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use hyper::header::HeaderValue;

    fn policy() -> Policy {
        Policy {
            bound: "127.0.0.1:8080".parse().unwrap(),
            allow_control: true,
            allow_remote_control: false,
            token: None,
        }
    }

    const HERE: IpAddr = IpAddr::V4(std::net::Ipv4Addr::LOCALHOST);

    #[test]
    fn host_names() {
        let p = policy();
        for ok in [
            "127.0.0.1:8080",
            "localhost:8080",
            "LOCALHOST:8080",
            "[::ffff:127.0.0.1]:8080",
        ] {
            assert!(p.names_us(ok, HERE), "{ok}");
        }
        for bad in [
            "evil.example:8080",
            "127.0.0.1:9999",
            // No port: HTTP's 80, another origin.
            "127.0.0.1",
            "localhost",
            // Another loopback address is another origin.
            "127.0.0.2:8080",
            "[::1]:8080",
            "",
            ":8080",
            "[::1",
            "10.0.0.1:8080",
            "localhost.:8080",
        ] {
            assert!(!p.names_us(bad, HERE), "{bad}");
        }
        // Bound to every address: the one the client reached, localhost
        // only on loopback.
        let any = Policy {
            bound: "0.0.0.0:8080".parse().unwrap(),
            ..policy()
        };
        let lan: IpAddr = "192.0.2.7".parse().unwrap();
        assert!(any.names_us("192.0.2.7:8080", lan));
        assert!(!any.names_us("localhost:8080", lan));
        assert!(!any.names_us("0.0.0.0:8080", lan));
        assert!(any.names_us("localhost:8080", HERE));
        // On port 80 the port may be left out.
        let p80 = Policy {
            bound: "127.0.0.1:80".parse().unwrap(),
            ..policy()
        };
        assert!(p80.names_us("localhost", HERE) && p80.names_us("127.0.0.1:80", HERE));
    }

    #[test]
    fn absolute_form_targets_are_refused() {
        let p = policy();
        for bad in ["http://evil.example/api/state", "http://127.0.0.1:8080/"] {
            let uri: hyper::Uri = bad.parse().unwrap();
            assert_eq!(p.check_target(&uri).unwrap_err().0, StatusCode::BAD_REQUEST);
        }
        assert!(p.check_target(&"/api/state?x=1".parse().unwrap()).is_ok());
    }

    #[test]
    fn control_origin_and_peer() {
        let p = policy();
        let local: SocketAddr = "127.0.0.1:5000".parse().unwrap();
        let remote: SocketAddr = "192.0.2.1:5000".parse().unwrap();
        let mut h = HeaderMap::new();
        assert!(p.check_control(local, HERE, &h).is_ok());
        assert_eq!(
            p.check_control(remote, HERE, &h).unwrap_err().0,
            StatusCode::FORBIDDEN
        );
        for foreign in [
            "http://evil.example",
            "http://localhost",
            "http://127.0.0.1",
            "http://127.0.0.2:8080",
            "https://localhost:8080",
            "null",
        ] {
            h.insert("origin", HeaderValue::from_static(foreign));
            assert_eq!(
                p.check_control(local, HERE, &h).unwrap_err().0,
                StatusCode::FORBIDDEN,
                "{foreign}"
            );
        }
        h.insert("origin", HeaderValue::from_static("http://localhost:8080"));
        assert!(p.check_control(local, HERE, &h).is_ok());
        h.insert("origin", HeaderValue::from_static("http://127.0.0.1:8080"));
        assert!(p.check_control(local, HERE, &h).is_ok());
        let mut r = policy();
        r.allow_remote_control = true;
        r.token = Some("abc".into());
        assert_eq!(
            r.check_control(remote, HERE, &h).unwrap_err().0,
            StatusCode::UNAUTHORIZED
        );
        for wrong in ["abd", "ab", "abcd", ""] {
            h.insert("x-triquint-token", HeaderValue::from_static(wrong));
            assert_eq!(
                r.check_control(remote, HERE, &h).unwrap_err().0,
                StatusCode::UNAUTHORIZED,
                "{wrong}"
            );
        }
        h.insert("x-triquint-token", HeaderValue::from_static("abc"));
        assert!(r.check_control(remote, HERE, &h).is_ok());
        let off = Policy {
            allow_control: false,
            ..policy()
        };
        assert_eq!(
            off.check_control(local, HERE, &HeaderMap::new())
                .unwrap_err()
                .0,
            StatusCode::FORBIDDEN
        );
    }

    #[test]
    fn rate_limit_refills() {
        let mut r = RateLimit::new(2, 1.0);
        let t = Instant::now();
        assert!(r.take(t).is_ok());
        assert!(r.take(t).is_ok());
        assert!(r.take(t).is_err());
        assert!(r.take(t + Duration::from_millis(1100)).is_ok());
    }
}
