//! An output that cannot be written: the error that marks a failure of the tool (exit status
//! 1) rather than of its input (exit status 2), wherever in a chain of contexts it stands.

/// An output that cannot be written (the tool failed: exit status 1), as the context of the
/// error that says why.
#[derive(Debug)]
pub struct OutputError(pub String);

impl std::fmt::Display for OutputError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for OutputError {}

impl OutputError {
    /// The file at `path` cannot be written.
    #[must_use]
    pub fn cannot_write(path: &std::path::Path) -> Self {
        OutputError(format!("cannot write `{}`", path.display()))
    }
}

/// Whether `e` is an output that could not be written ([`OutputError`] anywhere in its chain
/// of contexts): the tool failed (exit status 1), not the input.
#[must_use]
pub fn is_output_error(e: &anyhow::Error) -> bool {
    e.downcast_ref::<OutputError>().is_some()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn output_errors_are_found_under_any_context() {
        let direct = anyhow::Error::new(OutputError("cannot write".into()));
        assert!(is_output_error(&direct));
        let wrapped = anyhow::Error::new(std::io::Error::other("disk full"))
            .context(OutputError("cannot write `metrics.csv`".into()))
            .context("the run into `out` failed; nothing was written");
        assert!(is_output_error(&wrapped));
        let input = anyhow::anyhow!("`steps` = 0 is out of range").context("scenario file");
        assert!(!is_output_error(&input));
    }
}
