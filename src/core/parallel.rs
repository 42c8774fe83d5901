//! A list of independent jobs spread over two threads (the machine's cores): for studies and tests
//! that run the whole pipeline on many engines, and for a diagnosis's trials.

/// `f` on every item, on the calling thread and one helper taking turns (see
/// [`taking_turns_on_two_threads`]); the results in the order of the items. A panic in `f` is
/// carried on to the caller unchanged.
pub fn on_two_threads<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    // Never stopped (the progress always goes on), so every item has its result.
    taking_turns_on_two_threads(items, f, &mut |_| true).unwrap_or_default()
}

/// `f` on every item, on the calling thread and one helper, each taking the next item no one has
/// taken yet (so items of very different cost keep both threads busy); the results in the order of
/// the items, whichever thread computed them. Before its first item and after each item it
/// finishes, the calling thread gives `progress` the number of items finished so far; when
/// `progress` returns false no further item is started, and the result is `None` once the items
/// under way are finished. A panic in `f` is carried on to the caller unchanged.
pub fn taking_turns_on_two_threads<T: Sync, R: Send>(
    items: &[T],
    f: impl Fn(&T) -> R + Sync,
    progress: &mut dyn FnMut(usize) -> bool,
) -> Option<Vec<R>> {
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
    let (next, finished, stop) = (AtomicUsize::new(0), AtomicUsize::new(0), AtomicBool::new(false));
    // The next untaken item's result with its index, or `None` when all are taken.
    let take = || {
        let i = next.fetch_add(1, Ordering::Relaxed);
        let result = (i, f(items.get(i)?));
        finished.fetch_add(1, Ordering::Relaxed);
        Some(result)
    };
    let (mine, theirs) = std::thread::scope(|scope| {
        let helper = scope.spawn(|| {
            let mut theirs = Vec::new();
            while !stop.load(Ordering::Relaxed) {
                let Some(result) = take() else { break };
                theirs.push(result);
            }
            theirs
        });
        let mut mine = Vec::new();
        let mut go_on = progress(0);
        while go_on {
            let Some(result) = take() else { break };
            mine.push(result);
            go_on = progress(finished.load(Ordering::Relaxed));
        }
        stop.store(!go_on, Ordering::Relaxed);
        let theirs = helper.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        (go_on.then_some(mine), theirs)
    });
    let mut all: Vec<(usize, R)> = mine?.into_iter().chain(theirs).collect();
    all.sort_by_key(|(i, _)| *i);
    Some(all.into_iter().map(|(_, r)| r).collect())
}

#[cfg(test)]
mod tests {
    #[test]
    fn results_come_back_in_order() {
        let items: Vec<u32> = (0..7).collect();
        assert_eq!(super::on_two_threads(&items, |x| x * 10), vec![0, 10, 20, 30, 40, 50, 60]);
        assert!(super::on_two_threads(&[] as &[u32], |x| *x).is_empty());
    }

    #[test]
    fn turns_come_back_in_order_with_progress_counted() {
        let items: Vec<u64> = (0..9).collect();
        // Uneven costs, so the two threads finish items out of order.
        let slow = |x: &u64| {
            std::thread::sleep(std::time::Duration::from_millis(if x.is_multiple_of(3) { 15 } else { 1 }));
            x * 10
        };
        let mut counts = Vec::new();
        let out = super::taking_turns_on_two_threads(&items, slow, &mut |n| {
            counts.push(n);
            true
        });
        assert_eq!(out, Some((0..9).map(|x| x * 10).collect()));
        assert_eq!(counts.first(), Some(&0));
        assert!(counts.windows(2).all(|w| w[0] <= w[1]), "progress went back: {counts:?}");
        assert!(counts.iter().all(|&n| n <= items.len()));
        assert_eq!(super::taking_turns_on_two_threads(&[] as &[u64], |x| *x, &mut |_| true), Some(vec![]));
    }

    #[test]
    fn a_stop_starts_no_further_item() {
        use std::sync::atomic::{AtomicUsize, Ordering};
        let items: Vec<u64> = (0..200).collect();
        let started = AtomicUsize::new(0);
        let work = |x: &u64| {
            started.fetch_add(1, Ordering::Relaxed);
            std::thread::sleep(std::time::Duration::from_millis(3));
            *x
        };
        let out = super::taking_turns_on_two_threads(&items, work, &mut |n| n < 3);
        assert_eq!(out, None);
        // Stopped once three items had finished; the helper may have run a few more meanwhile,
        // not the 0.6 s of all of them.
        let started = started.load(Ordering::Relaxed);
        assert!((3..items.len()).contains(&started), "{started} items started");
        assert_eq!(super::taking_turns_on_two_threads(&items, |x| *x, &mut |_| false), None);
    }
}
