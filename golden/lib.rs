//! umbra's golden images live in this directory as insta snapshots (see README.md). This
//! crate is empty: it exists so that `cargo insta review` and `cargo insta pending-snapshots`,
//! which search the directories of workspace packages, find `golden/*.snap.new`.
