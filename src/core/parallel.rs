//! A list of independent jobs spread over two threads (the machine's cores): for studies and tests
//! that run the whole pipeline on many engines.

/// `f` on every item, the first half of the list on one thread and the second on another; the
/// results in the order of the items. A panic in `f` is carried on to the caller unchanged.
pub fn on_two_threads<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    let half = items.len().div_ceil(2);
    std::thread::scope(|scope| {
        let f = &f;
        let handles: Vec<_> = items
            .chunks(half.max(1))
            .map(|chunk| scope.spawn(move || chunk.iter().map(f).collect::<Vec<R>>()))
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic)))
            .collect()
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn results_come_back_in_order() {
        let items: Vec<u32> = (0..7).collect();
        assert_eq!(super::on_two_threads(&items, |x| x * 10), vec![0, 10, 20, 30, 40, 50, 60]);
        assert!(super::on_two_threads(&[] as &[u32], |x| *x).is_empty());
    }
}
