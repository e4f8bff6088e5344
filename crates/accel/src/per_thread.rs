//! [`per_thread_stack!`]: a traversal stack kept per thread and lent to each walk.
//!
//! On several threads a timed pass calls a structure's batch path once per chunk of a few
//! hundred queries, so a stack allocated and cleared per call (5–9 KB for the wide BVH's and
//! the k-d tree's walks) cost a tenth to a fifth of a fast packet call, on several threads only
//! (docs/experiments.md, "traversal stacks of the batch paths kept per thread"). A stack kept
//! per thread costs nothing per call.

/// Declares `fn NAME<R>(f: impl FnOnce(&mut T) -> R) -> R`, which runs `f` with this thread's
/// `T`, boxed and made by `MAKE` on the thread's first call. A walk started while another on
/// the same thread holds it (a tree walked from inside another tree's walk) gets a fresh one
/// of its own instead.
///
/// ```text
/// raybench_accel::per_thread_stack!(pub(crate) fn with_stack -> Stack = new_stack());
/// ```
#[macro_export]
macro_rules! per_thread_stack {
    ($(#[$attr:meta])* $vis:vis fn $name:ident -> $ty:ty = $make:expr) => {
        $(#[$attr])*
        $vis fn $name<R>(f: impl FnOnce(&mut $ty) -> R) -> R {
            ::std::thread_local! {
                static PER_THREAD_STACK: ::std::cell::RefCell<::std::boxed::Box<$ty>> =
                    ::std::cell::RefCell::new($make);
            }
            PER_THREAD_STACK.with(|s| match s.try_borrow_mut() {
                Ok(mut stack) => f(&mut stack),
                Err(_) => f(&mut $make),
            })
        }
    };
}
