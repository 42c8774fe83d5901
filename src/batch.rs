//! Project → pipeline → report, headless.
use anyhow::Result;

use crate::cli::BatchArgs;

pub fn run(_args: &BatchArgs) -> Result<()> {
    anyhow::bail!("not yet")
}
