//! Deterministic use of the machine's cores for independent fits (candidate refits,
//! cross-validation folds): each item is computed by exactly the same code whatever the thread
//! count, and the results come back in item order, so the diagnosis does not depend on it.

/// Most threads used (the target machine has 2 cores, shared).
pub const MAX_THREADS: usize = 2;

/// Threads to use: `RIGCTL_THREADS` (1..) when set, else the available parallelism, at most
/// [`MAX_THREADS`].
pub fn threads() -> usize {
    let avail = std::thread::available_parallelism().map_or(1, |n| n.get());
    std::env::var("RIGCTL_THREADS")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
        .filter(|n| *n >= 1)
        .unwrap_or(avail)
        .clamp(1, MAX_THREADS)
}

/// `f` of every item, in item order, computed on up to [`threads`] threads (item i on thread
/// `i % threads`).
pub fn map_ordered<T, R, F>(items: &[T], f: F) -> Vec<R>
where
    T: Sync,
    R: Send,
    F: Fn(&T) -> R + Sync,
{
    let n_threads = threads().min(items.len());
    if n_threads <= 1 {
        return items.iter().map(&f).collect();
    }
    let f = &f;
    let mut parts: Vec<Vec<(usize, R)>> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..n_threads)
            .map(|t| {
                s.spawn(move || {
                    items
                        .iter()
                        .enumerate()
                        .skip(t)
                        .step_by(n_threads)
                        .map(|(i, x)| (i, f(x)))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
            .collect()
    });
    let mut all: Vec<(usize, R)> = parts.drain(..).flatten().collect();
    all.sort_by_key(|(i, _)| *i);
    all.into_iter().map(|(_, r)| r).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn results_keep_the_item_order() {
        let items: Vec<usize> = (0..37).collect();
        let out = map_ordered(&items, |i| i * i);
        assert_eq!(out, items.iter().map(|i| i * i).collect::<Vec<_>>());
        assert!(map_ordered(&[] as &[usize], |i| *i).is_empty());
    }
}
