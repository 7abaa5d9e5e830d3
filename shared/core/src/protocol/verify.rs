//! The single check of which messages each role may send in which phase.

use super::client_msg::{ClientMsg, LobbyMsg, PhantomMsg};
use super::ids::Role;
use super::replicated::Phase;
use super::server_msg::Refusal;

/// Whether `role` may send `msg` during `phase`, checking only shape (role, phase, finite numbers,
/// speed bound); the server checks reach and state afterwards.
pub fn verify(role: Role, phase: Phase, msg: &ClientMsg) -> Result<(), Refusal> {
    use super::client_msg::ViveMsg as V;
    match msg {
        ClientMsg::Malformed(reason) => Err(Refusal::Malformed(reason.clone())),
        ClientMsg::Lobby(LobbyMsg::Ready | LobbyMsg::Leave) => Ok(()),
        ClientMsg::Lobby(LobbyMsg::Rematch) if matches!(phase, Phase::Won | Phase::Lost(_)) => Ok(()),
        ClientMsg::Lobby(LobbyMsg::Rematch) => Err(Refusal::WrongPhase(phase)),
        ClientMsg::Vive(_) if role != Role::Vive => Err(Refusal::WrongRole),
        // Phantom may warn in the lobby too, so the acknowledgement is welcome in every phase.
        ClientMsg::Vive(V::WarningSeen(_)) => Ok(()),
        ClientMsg::Phantom(_) if role != Role::Phantom => Err(Refusal::WrongRole),
        ClientMsg::Phantom(PhantomMsg::Warn(_) | PhantomMsg::ToolPose { .. }) if phase == Phase::Lobby => {
            // Harmless before the heist: lets Phantom try the device in the lobby.
            check_phantom_numbers(msg)
        }
        _ if phase != Phase::Heist => Err(Refusal::WrongPhase(phase)),
        ClientMsg::Vive(V::Move { direction, facing, .. }) => {
            if !direction.is_finite() || !facing.is_finite() {
                Err(Refusal::NotFinite)
            } else if direction.length_squared() > 1.0 + 1e-4 {
                Err(Refusal::TooFast)
            } else {
                Ok(())
            }
        }
        ClientMsg::Vive(V::Throw { target, .. }) if !target.is_finite() => Err(Refusal::NotFinite),
        ClientMsg::Vive(_) => Ok(()),
        ClientMsg::Phantom(_) => check_phantom_numbers(msg),
    }
}

fn check_phantom_numbers(msg: &ClientMsg) -> Result<(), Refusal> {
    match msg {
        ClientMsg::Phantom(PhantomMsg::ToolPose { position, rotation })
            if !position.is_finite() || !rotation.is_finite() =>
        {
            Err(Refusal::NotFinite)
        }
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec2;

    use super::super::{ItemId, ViveMsg};
    use super::*;

    fn mv(direction: Vec2) -> ClientMsg {
        ClientMsg::Vive(ViveMsg::Move { seq: 1, direction, gait: Default::default(), facing: 0.0 })
    }

    #[test]
    fn phantom_cannot_move_vive() {
        assert_eq!(verify(Role::Phantom, Phase::Heist, &mv(Vec2::X)), Err(Refusal::WrongRole));
    }

    #[test]
    fn vive_cannot_give_a_verdict() {
        let v = ClientMsg::Phantom(PhantomMsg::Verdict { item: ItemId(0), real: true });
        assert_eq!(verify(Role::Vive, Phase::Heist, &v), Err(Refusal::WrongRole));
    }

    #[test]
    fn moving_faster_than_allowed_is_refused() {
        assert_eq!(verify(Role::Vive, Phase::Heist, &mv(Vec2::new(3.0, 0.0))), Err(Refusal::TooFast));
        assert_eq!(verify(Role::Vive, Phase::Heist, &mv(Vec2::new(f32::NAN, 0.0))), Err(Refusal::NotFinite));
    }

    #[test]
    fn actions_wait_for_the_heist_but_ready_does_not() {
        assert_eq!(verify(Role::Vive, Phase::Lobby, &mv(Vec2::X)), Err(Refusal::WrongPhase(Phase::Lobby)));
        assert_eq!(verify(Role::Vive, Phase::Lobby, &ClientMsg::Lobby(LobbyMsg::Ready)), Ok(()));
        assert!(verify(Role::Vive, Phase::Won, &mv(Vec2::X)).is_err());
    }

    #[test]
    fn another_round_can_be_asked_only_after_a_result() {
        let rematch = ClientMsg::Lobby(LobbyMsg::Rematch);
        assert_eq!(verify(Role::Vive, Phase::Heist, &rematch), Err(Refusal::WrongPhase(Phase::Heist)));
        assert_eq!(verify(Role::Phantom, Phase::Lobby, &rematch), Err(Refusal::WrongPhase(Phase::Lobby)));
        assert_eq!(verify(Role::Phantom, Phase::Won, &rematch), Ok(()));
        let lost = Phase::Lost(super::super::LossReason::Time);
        assert_eq!(verify(Role::Vive, lost, &rematch), Ok(()));
    }
}
