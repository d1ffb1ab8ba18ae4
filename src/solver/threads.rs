//! The worker threads of a run's element loops (rayon): how many a request gets.

/// The worker threads to start for `--threads requested` on a machine with `cores` cores, and
/// the note to print when it is cut down: threads beyond the cores only slow the run (and
/// tens of thousands of them exhaust the machine).
pub fn thread_count(requested: usize, cores: usize) -> anyhow::Result<(usize, Option<String>)> {
    match requested {
        0 => anyhow::bail!("--threads must be at least 1"),
        n if n > cores => Ok((
            cores,
            Some(format!(
                "note: --threads {n} is more than the {cores} cores of this machine; using {cores}"
            )),
        )),
        n => Ok((n, None)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn threads_are_cut_to_the_cores_and_zero_is_refused() {
        assert_eq!(thread_count(2, 4).unwrap(), (2, None));
        assert_eq!(thread_count(4, 4).unwrap(), (4, None));
        let (n, note) = thread_count(100_000, 2).unwrap();
        assert_eq!(n, 2);
        assert_eq!(
            note.as_deref(),
            Some("note: --threads 100000 is more than the 2 cores of this machine; using 2")
        );
        let e = thread_count(0, 2).unwrap_err().to_string();
        assert!(e.contains("--threads"), "{e}");
    }
}
