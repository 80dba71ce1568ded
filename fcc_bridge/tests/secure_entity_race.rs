//! One secure participant (DDS Security's builtin plugins, the bridge's enclave of a keystore
//! made by `fcc-keystore`) on which one thread creates topics while others create readers and
//! writers, as a node's set-up thread and its spinner do at start-up: every creation finishes.
//!
//! The vendored rustdds read the participant's domain id (which locks the participant) as an
//! argument of the access-control check made with the security plugins locked, while
//! `DomainParticipant::create_topic` holds the participant's lock and waits for the plugins:
//! a lock-order inversion that hung the mission node at start-up now and then under load
//! (`tests/security/secure_stack.sh`, "I need my lock!!" naming the holder `main` at the
//! reader's check). Before the fix this test hung in 2 of 4 runs, after it in none of 23
//! (VENDOR.md). Creates a DDS participant: run it in a loopback-only namespace.

use fcc_ros::ros_node::{self, DdsEnv};
use rustdds::{QosPolicyBuilder, TopicKind};
use std::sync::mpsc;
use std::thread;
use std::time::Duration;

/// Creations per thread.
const ROUNDS: usize = 300;
/// Every thread is done well within this (the whole test takes 2–6 s); a deadlock never is.
const LIMIT: Duration = Duration::from_secs(90);

#[test]
fn topics_readers_and_writers_created_together_never_deadlock() {
    let dir = std::env::temp_dir().join(format!("fcc-entity-race-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_fcc-keystore"))
        .arg("create")
        .arg(&dir)
        .output()
        .expect("run fcc-keystore");
    assert!(out.status.success(), "fcc-keystore: {out:?}");
    let ctx = ros_node::context(DdsEnv {
        domain_id: 0,
        localhost_only: true,
        enclave_dir: Some(dir.join("enclaves/fcc/fcc_bridge")),
    })
    .expect("a secure participant on the bridge's enclave");
    let dp = ctx.domain_participant().clone();
    let qos = QosPolicyBuilder::new().build();
    // The bridge subscribes to setpoints and publishes odometry (its permissions).
    let sub_name = "rt/fcc/setpoint/velocity";
    let pub_name = "rt/fcc/state/odom";
    let ty = "std_msgs::msg::dds_::Empty_";
    let sub_topic = dp
        .create_topic(sub_name.into(), ty.into(), &qos, TopicKind::NoKey)
        .unwrap();
    let pub_topic = dp
        .create_topic(pub_name.into(), ty.into(), &qos, TopicKind::NoKey)
        .unwrap();
    let subscriber = dp.create_subscriber(&qos).unwrap();
    let publisher = dp.create_publisher(&qos).unwrap();

    let (done_tx, done_rx) = mpsc::channel::<&'static str>();
    let (d, q) = (dp.clone(), qos.clone());
    let mut i = 0;
    rounds(&done_tx, "topics", move || {
        i += 1;
        let name = if i % 2 == 0 { sub_name } else { pub_name };
        d.create_topic(name.into(), ty.into(), &q, TopicKind::NoKey)
            .expect("create_topic");
    });
    rounds(&done_tx, "readers", move || {
        drop(
            subscriber
                .create_datareader_no_key_cdr::<u8>(&sub_topic, None)
                .expect("create_datareader"),
        )
    });
    rounds(&done_tx, "writers", move || {
        drop(
            publisher
                .create_datawriter_no_key_cdr::<u8>(&pub_topic, None)
                .expect("create_datawriter"),
        )
    });
    let mut finished = Vec::new();
    while finished.len() < 3 {
        match done_rx.recv_timeout(LIMIT) {
            Ok(who) => finished.push(who),
            Err(_) => {
                // Leave the participant to the process exit: dropping it joins its threads.
                std::mem::forget(ctx);
                panic!(
                    "deadlock: after {LIMIT:?} only {finished:?} of topics, readers and writers \
                     finished {ROUNDS} creations each"
                );
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs `create` [`ROUNDS`] times on a thread of its own, then says `who` on `done`.
fn rounds(
    done: &mpsc::Sender<&'static str>,
    who: &'static str,
    mut create: impl FnMut() + Send + 'static,
) {
    let done = done.clone();
    thread::spawn(move || {
        for _ in 0..ROUNDS {
            create();
        }
        let _ = done.send(who);
    });
}
