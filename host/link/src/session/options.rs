//! Timing and policy of a session.

/// Timing and policy of a session.
#[derive(Clone, Debug, PartialEq)]
pub struct SessionOptions {
    pub fd: bool,
    /// Write the configuration before checking it (else only check).
    pub configure: bool,
    /// Most segments unacknowledged at once.
    pub window: usize,
    pub retransmit_timeout_us: u64,
    pub max_retransmits: u32,
    pub sync_period_us: u64,
    /// Sync period until every node reports a valid sync.
    pub fast_sync_period_us: u64,
    /// Start time ahead of the Start command.
    pub start_lead_us: u64,
    /// Waiting for nodes (heartbeats, acknowledgements).
    pub response_timeout_us: u64,
    /// A set-up command (configuration, Arm) not answered within this is
    /// sent again: a configuration refused or unanswered at most
    /// `setup_resends` times, Arm at most twice (see `ARM_RESENDS`).
    pub setup_retry_us: u64,
    pub setup_resends: u32,
    /// After the plan's end, how long nodes may take to report Idle.
    pub finish_grace_us: u64,
    /// Test hook: stop streaming after this many segments (provokes underrun).
    pub stall_after: Option<usize>,
    /// Only configure the nodes (and check the configuration), no motion.
    pub configure_only: bool,
    /// Clear faulted nodes before the upload (`upload --clear`); otherwise
    /// a faulted node ends the session before anything is sent.
    pub clear_faults: bool,
    /// Refuse to start when a node is not homed (every motion; not for
    /// configuring only).
    pub require_homed: bool,
    /// A feed override (per mille) sent once the configuration is checked
    /// (after its commit, which keeps an earlier override only within the
    /// new cap): how `upload --approach` carries the override to the plan.
    pub feed_override: Option<u16>,
    /// Send continuations compact where possible (`protocol::compact`);
    /// `false` sends every segment in full.
    pub compact: bool,
    /// Maintenance: open each configured drive's maintenance window
    /// (`UnlockCeilings`) before the writes, so the commit may raise its
    /// ceilings or widen its travel (`CeilingsLocked` otherwise).
    pub unlock_ceilings: bool,
}

impl Default for SessionOptions {
    fn default() -> Self {
        Self {
            fd: false,
            configure: true,
            window: 4,
            retransmit_timeout_us: 50_000,
            max_retransmits: 5,
            sync_period_us: 100_000,
            fast_sync_period_us: 10_000,
            start_lead_us: 50_000,
            response_timeout_us: 2_000_000,
            setup_retry_us: 30_000,
            setup_resends: 4,
            finish_grace_us: 5_000_000,
            stall_after: None,
            configure_only: false,
            clear_faults: false,
            require_homed: true,
            feed_override: None,
            compact: true,
            unlock_ceilings: false,
        }
    }
}
