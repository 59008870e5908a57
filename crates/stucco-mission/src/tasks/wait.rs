//! `wait_for_operator`: stops and waits for the operator's `continue`.

use super::{Behaviours, Task, TaskCx, TaskFailure, TaskStep, Thaw, drive_through};
use crate::behaviour::{Behaviour, BehaviourKind};
use crate::executive::EventKind;
use crate::task::OnTimeout;

/// Stands still until the operator answers, or gives up after a time.
#[derive(Clone, Debug)]
pub(crate) struct WaitForOperator {
    prompt: String,
    timeout_s: Option<f64>,
    on_timeout: OnTimeout,
    ways: Behaviours,
}

impl WaitForOperator {
    pub fn new(prompt: String, timeout_s: Option<f64>, on_timeout: OnTimeout) -> Self {
        WaitForOperator {
            prompt,
            timeout_s,
            on_timeout,
            ways: Behaviours::default(),
        }
    }
}

impl Task for WaitForOperator {
    fn start(&mut self, cx: &mut TaskCx<'_>, _: &mut Option<Thaw>) -> Result<(), TaskFailure> {
        self.ways.queue.push_back(Behaviour::hold());
        cx.emit(EventKind::OperatorPrompt {
            task: cx.index,
            prompt: self.prompt.clone(),
        });
        Ok(())
    }

    fn step(&mut self, cx: &mut TaskCx<'_>) -> TaskStep {
        if cx.answered {
            return TaskStep::Done;
        }
        let elapsed = cx.elapsed_s();
        if self.timeout_s.is_some_and(|t| elapsed > t) {
            return match self.on_timeout {
                OnTimeout::Continue => TaskStep::Done,
                OnTimeout::Fail => TaskStep::Failed(TaskFailure::NobodyAnswered),
            };
        }
        drive_through(&mut self.ways, cx)
    }

    fn behaviour(&self) -> Option<&BehaviourKind> {
        self.ways.kind()
    }

    fn clone_box(&self) -> Box<dyn Task> {
        Box::new(self.clone())
    }
}
