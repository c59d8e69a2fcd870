//! The fit's diagnostic trace: lines about what the stages decided (the coarse mesh's size, the tree's patches,
//! each round of the part rule, each refinement trial, SQUAREM's extrapolations). The core never prints: it hands
//! each line to the sink its caller installed on this thread ([`set_sink`]; the CLI's `--trace` prints them to
//! stderr), and formats nothing when there is none ([`enabled`]).

use std::cell::RefCell;

type Sink = Box<dyn FnMut(&str)>;

thread_local! {
    static SINK: RefCell<Option<Sink>> = const { RefCell::new(None) };
}

/// Installs `sink` for this thread's fits (None: no trace), returning the one it replaces.
pub fn set_sink(sink: Option<Sink>) -> Option<Sink> {
    SINK.with(|s| std::mem::replace(&mut *s.borrow_mut(), sink))
}

/// Whether a sink is installed: the lines are only formatted then.
pub fn enabled() -> bool {
    SINK.with(|s| s.borrow().is_some())
}

/// Hands `line` to the sink, if any.
pub fn emit(line: &str) {
    SINK.with(|s| {
        if let Some(sink) = s.borrow_mut().as_mut() {
            sink(line);
        }
    });
}

/// `trace_line!("format", args...)`: one line of the trace, formatted only when a sink is installed.
#[macro_export]
macro_rules! trace_line {
    ($($t:tt)*) => {
        if $crate::trace::enabled() {
            $crate::trace::emit(&format!($($t)*));
        }
    };
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::rc::Rc;

    #[test]
    fn lines_reach_the_sink_only_while_one_is_installed() {
        let got = Rc::new(RefCell::new(Vec::new()));
        crate::trace_line!("before {}", 1);
        let kept = got.clone();
        set_sink(Some(Box::new(move |l: &str| kept.borrow_mut().push(l.to_string()))));
        assert!(enabled());
        crate::trace_line!("tree: {} patches", 12);
        set_sink(None);
        crate::trace_line!("after");
        assert_eq!(*got.borrow(), vec!["tree: 12 patches".to_string()]);
    }
}
