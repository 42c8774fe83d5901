//! The linear part of recent structures, kept so that a structure differing from one of them only in
//! the parameters of blocks after the linear part (a rate limit, the stand's dynamics, the map's
//! kink, a calibration drift) is assembled without simulating its roots and spool again. What
//! Levenberg–Marquardt's finite-difference Jacobian asks for in every such parameter's column, and
//! what the screening of such a block's starting points asks for in every guess. The result is the
//! same, bit for bit: the linear part depends on nothing else.
use std::collections::VecDeque;
use std::rc::Rc;

use super::{Assembled, FitData, LinearPart, Structure, assemble_from, linear_parts};

/// Linear parts kept: more than the parameters of any structure the fits move (roots and effect
/// parameters, a dozen or so), so that the point a Jacobian is taken at is still kept when the last
/// of its columns is evaluated. Each is one simulated response (at most the fit's sample budget).
const KEPT: usize = 24;

/// Recent structures' linear parts, oldest first, each under the text of what it depends on.
#[derive(Default)]
pub(super) struct LinearMemo {
    kept: VecDeque<(String, Rc<LinearPart>)>,
}

impl LinearMemo {
    /// [`super::assemble`], with the linear part taken from a kept structure that shares it.
    pub(super) fn assemble(&mut self, s: &Structure, data: &FitData) -> Option<Assembled> {
        self.assemble_each(&[Some(s)], data).pop().flatten()
    }

    /// [`LinearMemo::assemble`] of each structure (`None` passes through): the linear parts not
    /// kept are simulated together ([`linear_parts`]), each once.
    pub(super) fn assemble_each(
        &mut self,
        structures: &[Option<&Structure>],
        data: &FitData,
    ) -> Vec<Option<Assembled>> {
        let keys: Vec<Option<String>> = structures.iter().map(|s| s.map(key)).collect();
        // Each key's part as kept now, before the new ones push any out.
        let mut parts: Vec<(String, Rc<LinearPart>)> = Vec::new();
        let mut missing: Vec<(String, &Structure)> = Vec::new();
        for (k, s) in keys.iter().zip(structures) {
            let (Some(k), Some(s)) = (k, s) else { continue };
            if parts.iter().any(|(p, _)| p == k) || missing.iter().any(|(m, _)| m == k) {
                continue;
            }
            match self.kept.iter().find(|(kept, _)| kept == k) {
                Some((_, part)) => parts.push((k.clone(), Rc::clone(part))),
                None => missing.push((k.clone(), s)),
            }
        }
        let simulated = linear_parts(&missing.iter().map(|(_, s)| *s).collect::<Vec<_>>(), data);
        for ((k, _), part) in missing.into_iter().zip(simulated) {
            let Some(part) = part else { continue };
            let part = Rc::new(part);
            if self.kept.len() == KEPT {
                self.kept.pop_front();
            }
            self.kept.push_back((k.clone(), Rc::clone(&part)));
            parts.push((k, part));
        }
        keys.iter()
            .zip(structures)
            .map(|(k, s)| {
                let (k, s) = (k.as_ref()?, (*s)?);
                let (_, part) = parts.iter().find(|(p, _)| p == k)?;
                assemble_from(s, data, part)
            })
            .collect()
    }
}

/// What a structure's linear part depends on, as text: the roots, the dead time and the blocks
/// that shape it, every number written exactly (`{:?}` writes the shortest text that reads back to
/// the same bits, and tells −0 from 0).
fn key(s: &Structure) -> String {
    let shaping: Vec<_> = s.effects.iter().filter(|e| e.shapes_linear_part()).collect();
    format!("{:?}|{:?}|{}|{:?}", s.poles, s.zeros, s.delay, shaping)
}
