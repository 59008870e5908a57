//! `localize`: stands still until the pose is known well enough.

use super::{Behaviours, Task, TaskCx, TaskFailure, TaskStep, Thaw, drive_through};
use crate::behaviour::{Behaviour, BehaviourKind};

/// Stands still until the position is known to `max_sigma_m`.
#[derive(Clone, Debug)]
pub(crate) struct Localize {
    max_sigma_m: f64,
    timeout_s: f64,
    ways: Behaviours,
}

impl Localize {
    pub fn new(max_sigma_m: f64, timeout_s: f64) -> Self {
        Localize {
            max_sigma_m,
            timeout_s,
            ways: Behaviours::default(),
        }
    }
}

impl Task for Localize {
    fn start(&mut self, _: &mut TaskCx<'_>, _: &mut Option<Thaw>) -> Result<(), TaskFailure> {
        self.ways.queue.push_back(Behaviour::hold());
        Ok(())
    }

    fn step(&mut self, cx: &mut TaskCx<'_>) -> TaskStep {
        if cx.est.position_sigma_m <= self.max_sigma_m {
            return TaskStep::Done;
        }
        let timeout_s = self.timeout_s;
        if cx.elapsed_s() > timeout_s {
            return TaskStep::Failed(TaskFailure::NotLocalized {
                sigma_m: cx.est.position_sigma_m,
                timeout_s,
            });
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
