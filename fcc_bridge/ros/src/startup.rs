//! Start-up protection shared by `fcc-bridge` and `fcc-mission`: the DDS set-up on a thread of
//! its own under a watchdog, a restart (re-exec) after a stalled set-up, and SIGTERM / SIGINT
//! served by a thread independent of the tokio runtime.
//!
//! rustdds 0.15.1 can deadlock while endpoints are created when other participants are being
//! discovered at the same moment (several nodes starting together): its discovery thread holds
//! the DiscoveryDB read lock while it blocks on the full 32-slot notification channel to the
//! participant's event loop (`Discovery::add_local_reader`), the event loop waits for that read
//! lock behind our thread's queued write lock (`create_datareader`/`create_datawriter`, std's
//! RwLock lets no new reader past a waiting writer), and our thread waits for the discovery
//! thread's read lock. Nothing moves again. The stalled participant cannot be recovered in the
//! process, so the program starts afresh.
//!
//! Environment (`P` is the program's prefix, e.g. `FCC_BRIDGE`, `FCC_MISSION`):
//! `P_DDS_STARTUP_TIMEOUT_MS` (the watchdog, default [`DDS_STARTUP_TIMEOUT`]),
//! `P_DDS_ATTEMPT` (set by the restart), `P_TEST_STALL_DDS` (test hook: the set-up blocks for
//! good, as the deadlock does).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// How long the DDS set-up may take before the program gives up on it (normally some tens of
/// ms; `P_DDS_STARTUP_TIMEOUT_MS` overrides it).
pub const DDS_STARTUP_TIMEOUT: Duration = Duration::from_secs(5);

/// How often the program starts after a stalled DDS start-up before giving up (in all).
pub const DDS_START_ATTEMPTS: u32 = 3;

/// The program: its name (message prefix) and its environment-variable prefix.
#[derive(Clone, Copy, Debug)]
pub struct App {
    /// e.g. `fcc-bridge`.
    pub name: &'static str,
    /// e.g. `FCC_BRIDGE`.
    pub env_prefix: &'static str,
}

/// The step the DDS set-up is at (named in the stall error).
#[derive(Clone, Default)]
pub struct Step(Arc<Mutex<String>>);

impl Step {
    pub fn set(&self, s: &str) {
        *self.0.lock().unwrap_or_else(|e| e.into_inner()) = s.to_string();
    }
    pub fn get(&self) -> String {
        self.0.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }
}

/// Why [`App::setup_dds`] returned no result.
#[derive(Debug)]
pub enum SetupError {
    /// The set-up did not finish in time (message names the step).
    Stalled(String),
    /// The set-up thread could not be started or died.
    Thread(String),
}

impl App {
    fn var(&self, suffix: &str) -> String {
        format!("{}_{suffix}", self.env_prefix)
    }

    /// The watchdog's limit.
    pub fn startup_timeout(&self) -> Duration {
        std::env::var(self.var("DDS_STARTUP_TIMEOUT_MS"))
            .ok()
            .and_then(|v| v.trim().parse::<u64>().ok())
            .map(Duration::from_millis)
            .unwrap_or(DDS_STARTUP_TIMEOUT)
    }

    /// Run the blocking DDS set-up `f` on a thread of its own (inside the current tokio
    /// runtime's context, for `tokio::spawn`), under the watchdog. The runtime stays free (and
    /// the signals are served) while it runs. If the set-up finishes after the watchdog gave up
    /// its result is leaked, never dropped (rustdds joins its threads on drop).
    pub async fn setup_dds<T, F>(&self, f: F) -> Result<T, SetupError>
    where
        T: Send + 'static,
        F: FnOnce(&Step) -> T + Send + 'static,
    {
        let handle = tokio::runtime::Handle::current();
        let (tx, rx) = tokio::sync::oneshot::channel();
        let step = Step::default();
        let st = step.clone();
        let hook = self.var("TEST_STALL_DDS");
        std::thread::Builder::new()
            .name("dds-setup".into())
            .spawn(move || {
                let _rt = handle.enter();
                if std::env::var_os(&hook).is_some() {
                    // Test hook: behave as the rustdds deadlock does (block for good).
                    st.set(&format!("creating the DDS participant ({hook})"));
                    loop {
                        std::thread::park();
                    }
                }
                let r = f(&st);
                if let Err(r) = tx.send(r) {
                    std::mem::forget(r);
                }
            })
            .map_err(|e| SetupError::Thread(format!("{e}")))?;
        let limit = self.startup_timeout();
        match tokio::time::timeout(limit, rx).await {
            Ok(Ok(r)) => Ok(r),
            Ok(Err(_)) => Err(SetupError::Thread("the DDS set-up thread failed".into())),
            Err(_) => Err(SetupError::Stalled(format!(
                "DDS start-up stalled for {:.1} s while {} (rustdds deadlock when several \
                 participants start together)",
                limit.as_secs_f64(),
                step.get()
            ))),
        }
    }

    /// Re-execute the program after a stalled DDS start-up (same pid, arguments and
    /// environment; at most [`DDS_START_ATTEMPTS`] in all, counted in `P_DDS_ATTEMPT`);
    /// returns when no attempt is left or exec fails.
    pub fn restart_after_stall(&self, e: &str) {
        use std::os::unix::process::CommandExt;
        let var = self.var("DDS_ATTEMPT");
        let attempt: u32 = std::env::var(&var)
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(1);
        if attempt >= DDS_START_ATTEMPTS {
            return;
        }
        eprintln!(
            "{}: {e}; restarting (attempt {} of {DDS_START_ATTEMPTS})",
            self.name,
            attempt + 1
        );
        let exe = std::env::current_exe().unwrap_or_else(|_| "/proc/self/exe".into());
        let err = std::process::Command::new(exe)
            .args(std::env::args_os().skip(1))
            .env(var, (attempt + 1).to_string())
            .exec();
        eprintln!("{}: cannot restart: {err}", self.name);
    }
}

/// SIGTERM / SIGINT, served by a thread of their own (not by the tokio runtime, which a
/// blocking call could hold up). The first signal asks the program to stop; if it has not begun
/// stopping within [`Stop::GRACE`] — or at a second signal — the process exits at once.
pub struct Stop {
    rx: tokio::sync::watch::Receiver<bool>,
    stopping: Arc<AtomicBool>,
}

impl Stop {
    pub const GRACE: Duration = Duration::from_millis(1500);

    pub fn install(app: App) -> std::io::Result<Stop> {
        use signal_hook::consts::{SIGINT, SIGTERM};
        let mut signals = signal_hook::iterator::Signals::new([SIGTERM, SIGINT])?;
        let (tx, rx) = tokio::sync::watch::channel(false);
        let stopping = Arc::new(AtomicBool::new(false));
        let st = stopping.clone();
        std::thread::Builder::new()
            .name("signals".into())
            .spawn(move || {
                let name = |s: i32| if s == SIGINT { "SIGINT" } else { "SIGTERM" };
                let mut first = true;
                for sig in signals.forever() {
                    if !first {
                        eprintln!("{}: second {}: exiting now", app.name, name(sig));
                        std::process::exit(1);
                    }
                    first = false;
                    let _ = tx.send(true);
                    let st = st.clone();
                    let _ = std::thread::Builder::new()
                        .name("stop-deadline".into())
                        .spawn(move || {
                            std::thread::sleep(Stop::GRACE);
                            if !st.load(Ordering::SeqCst) {
                                eprintln!(
                                    "{}: {} but it did not stop within {} ms: exiting now",
                                    app.name,
                                    name(sig),
                                    Stop::GRACE.as_millis()
                                );
                                std::process::exit(1);
                            }
                        });
                }
            })?;
        Ok(Stop { rx, stopping })
    }

    /// Resolves at the first SIGTERM / SIGINT.
    pub async fn wait(&self) {
        let mut rx = self.rx.clone();
        let _ = rx.wait_for(|s| *s).await;
    }

    /// The program has stopped running (it finishes up and exits).
    pub fn stopping(&self) {
        self.stopping.store(true, Ordering::SeqCst);
    }
}
