//! The linear part of recent structures, kept so that a structure differing from one of them only in
//! the parameters of blocks after the linear part (a rate limit, the stand's dynamics, the map's
//! kink, a calibration drift) is assembled without simulating its roots and spool again. What
//! Levenberg–Marquardt's finite-difference Jacobian asks for in every such parameter's column, and
//! what the screening of such a block's starting points asks for in every guess. The result is the
//! same, bit for bit: the linear part depends on nothing else.
use std::collections::VecDeque;
use std::rc::Rc;

use super::{Assembled, FitData, LinearPart, Structure, assemble_from, linear_part};

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
        let key = key(s);
        let part = match self.kept.iter().find(|(k, _)| *k == key) {
            Some((_, part)) => Rc::clone(part),
            None => {
                let part = Rc::new(linear_part(s, data)?);
                if self.kept.len() == KEPT {
                    self.kept.pop_front();
                }
                self.kept.push_back((key, Rc::clone(&part)));
                part
            }
        };
        assemble_from(s, data, &part)
    }
}

/// What a structure's linear part depends on, as text: the roots, the dead time and the blocks
/// that shape it, every number written exactly (`{:?}` writes the shortest text that reads back to
/// the same bits, and tells −0 from 0).
fn key(s: &Structure) -> String {
    let shaping: Vec<_> = s.effects.iter().filter(|e| e.shapes_linear_part()).collect();
    format!("{:?}|{:?}|{}|{:?}", s.poles, s.zeros, s.delay, shaping)
}
