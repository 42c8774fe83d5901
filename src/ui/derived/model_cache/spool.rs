//! The shaft speed's finished model handed to the other outputs of the cache, as the batch does
//! after every output's loop (`workflow::model::share_spool`): they share its spool blocks or are
//! read off it, and rebuild when it changes.
use std::sync::Arc;

use super::{IdentCache, OutputCache};
use crate::core::effects::ExtendedModel;
use crate::workflow::model;

impl IdentCache {
    /// Give every output other than the shaft speed the speed's finished model, whose spool blocks
    /// its model shares (`workflow::model::share_spool`, as the batch does); each rebuilds when what
    /// it shares changes. While the speed's model is being finished the others keep theirs.
    pub(super) fn share_the_spool(&mut self) {
        let names: Vec<String> = self.outputs.iter().map(|o| o.name.clone()).collect();
        let speed = model::spool_output(&names).map(str::to_owned);
        let spool = match &speed {
            Some(speed) => match self.output(speed).and_then(OutputCache::finished_spool) {
                Some(spool) => spool,
                None => return,
            },
            None => None,
        };
        for output in self.outputs.iter_mut().filter(|o| Some(&o.name) != speed.as_ref()) {
            output.set_spool(spool.clone());
        }
    }
}

impl OutputCache {
    /// What the other outputs share of this model, when this is a shaft speed whose model is
    /// finished ([`model::spool_part`]): `Some(None)` when it has no model of its own to share,
    /// `None` while it is being finished (the others keep what they share until it is).
    fn finished_spool(&self) -> Option<Option<Arc<ExtendedModel>>> {
        match &self.live {
            Ok(live) if live.finishing => None,
            Ok(live) => {
                // A speed whose requested effects could not be added has no finished model to share
                // (the batch refuses it); one with none requested shares its model as identified.
                let failed = live.effects.model.is_none() && !live.effects.requested.is_empty();
                let finished = (!failed).then(|| live.current_model());
                Some(finished.as_ref().and_then(model::spool_part).map(Arc::new))
            }
            Err(_) if self.finishing.is_some() => None,
            Err(_) => Some(None),
        }
    }

    /// Share the speed's model `spool` from now on (its spool blocks, and the whole model to read
    /// off): rebuild when it changes.
    fn set_spool(&mut self, spool: Option<Arc<ExtendedModel>>) {
        if self.spool.as_deref() != spool.as_deref() {
            self.spool = spool;
            self.rebuild();
        }
    }
}
