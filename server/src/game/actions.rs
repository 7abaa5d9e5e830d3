//! Vive's and Phantom's actions: each checks reach and state, then changes the game or refuses.

use glam::Vec2;
use heist_shared::protocol::{
    CaseId, Gait, GameEvent, ItemId, ItemKind, ItemPlace, NoiseKind, PhantomMsg, PhantomTool, Phase, Refusal, Role,
    ServerMsg, Stance, VerdictOutcome, ViveMsg, WorkbenchCopy,
};
use heist_shared::rules;

use super::{Game, Outgoing};

impl Game {
    pub(super) fn apply_vive(&mut self, msg: &ViveMsg) -> Result<(), Refusal> {
        match *msg {
            ViveMsg::Move { seq, direction, gait, facing } => {
                let newest = self.vive.inputs.back().map_or(self.vive.last_input_seq, |i| i.seq);
                if seq <= newest {
                    return Ok(()); // old or repeated: already applied or queued
                }
                let stance = match gait {
                    Gait::Run => Stance::Running,
                    Gait::Crouch => Stance::Crouching,
                    Gait::Walk => Stance::Standing,
                };
                if self.vive.inputs.len() >= super::MAX_QUEUED_INPUTS {
                    self.vive.inputs.pop_front();
                }
                let speed = rules::gait_speed(gait);
                self.vive.inputs.push_back(super::MoveInput { seq, direction, speed, stance, facing });
                Ok(())
            }
            ViveMsg::WarningSeen(kind) => {
                self.outgoing.push(Outgoing::To(Role::Phantom, ServerMsg::Event(GameEvent::WarningSeen(kind))));
                Ok(())
            }
            _ if self.phase != Phase::Heist => self.apply_vive_action(msg),
            _ => {
                self.fast_forward_inputs(super::TICK_S);
                self.apply_vive_action(msg)
            }
        }
    }

    fn apply_vive_action(&mut self, msg: &ViveMsg) -> Result<(), Refusal> {
        match *msg {
            ViveMsg::Move { .. } | ViveMsg::WarningSeen(_) => Ok(()),
            ViveMsg::Break(case) => self.break_case(case),
            ViveMsg::PickUp(item) => self.pick_up(item),
            ViveMsg::Drop(item) => {
                self.take_from_hands(item)?;
                self.items[usize::from(item.0)].place = ItemPlace::Floor(self.vive.position);
                Ok(())
            }
            ViveMsg::Throw { item, target } => self.throw(item, target),
            ViveMsg::PlaceOnWorkbench(item) => self.place_on_workbench(item),
        }
    }

    pub(super) fn apply_phantom(&mut self, msg: &PhantomMsg) -> Result<(), Refusal> {
        match *msg {
            PhantomMsg::Verdict { item, real } => self.verdict(item, real),
            PhantomMsg::ToolPose { position, rotation } => {
                self.tool = PhantomTool { position, rotation };
                Ok(())
            }
            PhantomMsg::Warn(kind) => {
                // To Vive, and back to Phantom as the confirmation that it went out.
                self.outgoing.push(Outgoing::All(ServerMsg::Event(GameEvent::Warning(kind))));
                Ok(())
            }
        }
    }

    fn in_reach(&self, p: Vec2) -> Result<(), Refusal> {
        if self.vive.position.distance(p) <= rules::REACH { Ok(()) } else { Err(Refusal::OutOfReach) }
    }

    fn break_case(&mut self, id: CaseId) -> Result<(), Refusal> {
        let case = self.case(id)?;
        if case.broken {
            return Err(Refusal::AlreadyBroken);
        }
        self.in_reach(case.position)?;
        let at = case.position;
        self.cases[usize::from(id.0)].broken = true;
        self.event(GameEvent::CaseBroken(id));
        self.noise(NoiseKind::Glass, at, rules::GLASS_LOUDNESS);
        Ok(())
    }

    fn pick_up(&mut self, id: ItemId) -> Result<(), Refusal> {
        let item = self.item(id)?;
        let at = match item.place {
            ItemPlace::Floor(p) => p,
            ItemPlace::InCase(c) => {
                let case = self.case(c)?;
                if !case.broken {
                    return Err(Refusal::CaseIntact);
                }
                case.position
            }
            _ => return Err(Refusal::OutOfReach),
        };
        self.in_reach(at)?;
        if self.vive.carrying.len() >= rules::CARRY_LIMIT {
            return Err(Refusal::HandsFull);
        }
        self.items[usize::from(id.0)].place = ItemPlace::Carried;
        self.vive.carrying.push(id);
        self.event(GameEvent::PickedUp(id));
        Ok(())
    }

    fn take_from_hands(&mut self, id: ItemId) -> Result<(), Refusal> {
        let pos = self.vive.carrying.iter().position(|&c| c == id).ok_or(Refusal::NotCarried)?;
        self.vive.carrying.remove(pos);
        Ok(())
    }

    fn throw(&mut self, id: ItemId, target: Vec2) -> Result<(), Refusal> {
        if !self.vive.carrying.contains(&id) {
            return Err(Refusal::NotCarried);
        }
        self.take_from_hands(id)?;
        let landing = self.walls.throw_landing(&self.level, self.vive.position, target);
        self.items[usize::from(id.0)].place = ItemPlace::Floor(landing);
        self.noise(NoiseKind::Thud, landing, rules::THUD_LOUDNESS);
        Ok(())
    }

    fn place_on_workbench(&mut self, id: ItemId) -> Result<(), Refusal> {
        if !self.vive.carrying.contains(&id) {
            return Err(Refusal::NotCarried);
        }
        let item = self.item(id)?;
        if item.truth.is_none() || !matches!(item.kind, ItemKind::Copy { .. }) {
            return Err(Refusal::NotACopy);
        }
        if self.workbench.is_some() {
            return Err(Refusal::WorkbenchBusy);
        }
        self.in_reach(self.level.workbench)?;
        self.take_from_hands(id)?;
        self.items[usize::from(id.0)].place = ItemPlace::Workbench;
        self.workbench = Some(id);
        self.event(GameEvent::Delivered(id));
        if let Some(copy) = self.workbench_copy(id) {
            self.outgoing.push(Outgoing::To(Role::Phantom, ServerMsg::Workbench(copy)));
        }
        Ok(())
    }

    /// What Phantom is sent of the copy `id` on the workbench: its true geometry and material.
    pub(super) fn workbench_copy(&self, id: ItemId) -> Option<WorkbenchCopy> {
        let truth = self.items.get(usize::from(id.0))?.truth.as_ref()?;
        Some(WorkbenchCopy { item: id, mesh: truth.mesh.clone(), material: truth.material })
    }

    fn verdict(&mut self, id: ItemId, declared_real: bool) -> Result<(), Refusal> {
        if self.workbench != Some(id) {
            return Err(Refusal::NotOnWorkbench);
        }
        let truth = self.item(id)?.truth.as_ref().ok_or(Refusal::NotACopy)?;
        let (real, target) = (truth.real, truth.target);
        let outcome = match (real, declared_real) {
            (true, true) => VerdictOutcome::Secured,
            (false, false) => VerdictOutcome::Discarded,
            _ => VerdictOutcome::Wrong,
        };
        self.event(GameEvent::Verdict { item: id, declared_real, outcome });
        match outcome {
            VerdictOutcome::Secured => {
                self.items[usize::from(id.0)].place = ItemPlace::Secured;
                self.targets[target].secured = true;
                self.workbench = None;
                if self.targets.iter().all(|t| t.secured) {
                    self.set_phase(Phase::Won);
                }
            }
            VerdictOutcome::Discarded => {
                self.items[usize::from(id.0)].place = ItemPlace::Discarded;
                self.workbench = None;
            }
            VerdictOutcome::Wrong => self.raise_alarm(),
        }
        Ok(())
    }
}
