//! Orchestration: backends by id ([`registry`], with the test doubles in [`fake`]), the Mesa
//! build a worker runs on ([`mesa_build`], with the hardware drivers it may carry:
//! [`hw_driver`], and its own C library where it carries one:
//! [`own_libc`]), one process per backend ([`worker`], [`child`]), which dies with its parent
//! ([`orphan`]) and says where a fault killed it ([`crash_report`]), kept in a [`pool`] under a memory limit ([`memory_limit`]) and fed by the one
//! [`scheduler`] every command uses (sessions that restart a dead worker, reruns, queues), behaviour cards measured in a worker of their own ([`cards`]) and the
//! terminal's progress line ([`progress`]). Uses the judge; knows no command.

pub mod cards;
pub mod child;
pub mod crash_report;
pub mod fake;
pub mod hw_driver;
pub mod interrupt;
pub mod memory_limit;
pub mod mesa_build;
pub mod orphan;
pub mod own_libc;
pub mod pool;
pub mod progress;
pub mod registry;
pub mod scheduler;
pub mod stderr_log;
pub mod worker;
