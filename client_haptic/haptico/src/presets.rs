//! Specs of common devices, from CHAI3D's device tables and the makers' data sheets.
//!
//! You need this module to configure the simulated device or the safety layer for a real model.
//! Values not given in those tables (continuous force of some models, damping limits) are marked
//! "assumed" and are conservative.

use crate::DeviceSpecs;

/// 3D Systems Touch: 3.3 N peak, 0.88 N continuous, 400 N/m, 75 mm workspace radius; 6-DOF sensed, 3 actuated.
pub fn touch() -> DeviceSpecs {
    DeviceSpecs {
        name: "3D Systems Touch",
        sensed_dof: 6,
        actuated_dof: 3,
        peak_force_n: 3.3,
        continuous_force_n: 0.88,
        max_torque_nm: 0.0,
        max_stiffness_n_per_m: 400.0,
        max_damping_ns_per_m: 2.0, // assumed
        workspace_radius_m: 0.075,
    }
}

/// SensAble Phantom Omni: 3.3 N peak, 0.88 N continuous, 700 N/m.
pub fn phantom_omni() -> DeviceSpecs {
    DeviceSpecs {
        name: "Phantom Omni",
        max_stiffness_n_per_m: 700.0,
        max_damping_ns_per_m: 3.5, // assumed
        workspace_radius_m: 0.08,
        ..touch()
    }
}

/// SensAble Phantom Desktop: 7.9 N peak, 1000 N/m.
pub fn phantom_desktop() -> DeviceSpecs {
    DeviceSpecs {
        name: "Phantom Desktop",
        peak_force_n: 7.9,
        continuous_force_n: 1.75,
        max_stiffness_n_per_m: 1000.0,
        max_damping_ns_per_m: 5.0, // assumed
        workspace_radius_m: 0.08,
        ..touch()
    }
}

/// SensAble Phantom Premium 1.5 6-DOF: 8.5 N peak, 0.188 N·m, 800 N/m.
pub fn phantom_premium_6dof() -> DeviceSpecs {
    DeviceSpecs {
        name: "Phantom Premium 1.5 6-DOF",
        sensed_dof: 6,
        actuated_dof: 6,
        peak_force_n: 8.5,
        continuous_force_n: 1.4,
        max_torque_nm: 0.188,
        max_stiffness_n_per_m: 800.0,
        max_damping_ns_per_m: 4.0, // assumed
        workspace_radius_m: 0.1,
    }
}

/// Novint Falcon: 8 N peak, 3000 N/m, 40 mm workspace radius; 3-DOF.
pub fn falcon() -> DeviceSpecs {
    DeviceSpecs {
        name: "Novint Falcon",
        sensed_dof: 3,
        actuated_dof: 3,
        peak_force_n: 8.0,
        continuous_force_n: 8.0, // assumed: no separate figure published
        max_torque_nm: 0.0,
        max_stiffness_n_per_m: 3000.0,
        max_damping_ns_per_m: 20.0, // assumed
        workspace_radius_m: 0.04,
    }
}

/// Haply Inverse3: 10 N peak, 4 N held (Haply's "maximum force over 80 % of the workspace"), 1 N/mm,
/// a 510 × 460 × 230 mm workspace (the ball inside it: 115 mm), refreshed at up to 4 kHz; 3-DOF (the
/// VerseGrip's orientation is not read). Figures from Haply's published specification, read from a public
/// copy of the product page (Haply's own site was not reachable from here); damping is assumed.
pub fn inverse3() -> DeviceSpecs {
    DeviceSpecs {
        name: "Haply Inverse3",
        sensed_dof: 3,
        actuated_dof: 3,
        peak_force_n: 10.0,
        continuous_force_n: 4.0,
        max_torque_nm: 0.0,
        max_stiffness_n_per_m: 1000.0,
        max_damping_ns_per_m: 5.0, // assumed, as the Phantom Desktop's
        workspace_radius_m: 0.115,
    }
}

/// Force Dimension omega.x: 12 N, 5000 N/m, 75 mm workspace radius.
pub fn omega() -> DeviceSpecs {
    DeviceSpecs {
        name: "Force Dimension omega.x",
        sensed_dof: 6,
        actuated_dof: 3,
        peak_force_n: 12.0,
        continuous_force_n: 12.0,
        max_torque_nm: 0.0,
        max_stiffness_n_per_m: 5000.0,
        max_damping_ns_per_m: 20.0, // assumed
        workspace_radius_m: 0.075,
    }
}

/// Force Dimension sigma.7: 12 N, 0.2 N·m; 6-DOF actuated (plus grip).
pub fn sigma7() -> DeviceSpecs {
    DeviceSpecs {
        name: "Force Dimension sigma.7",
        sensed_dof: 6,
        actuated_dof: 6,
        peak_force_n: 12.0,
        continuous_force_n: 12.0,
        max_torque_nm: 0.2,
        max_stiffness_n_per_m: 4000.0, // assumed
        max_damping_ns_per_m: 20.0,    // assumed
        workspace_radius_m: 0.095,
    }
}

/// Force Dimension delta.3: 20 N.
pub fn delta3() -> DeviceSpecs {
    DeviceSpecs {
        name: "Force Dimension delta.3",
        sensed_dof: 3,
        actuated_dof: 3,
        peak_force_n: 20.0,
        continuous_force_n: 20.0,
        max_torque_nm: 0.0,
        max_stiffness_n_per_m: 14500.0, // assumed
        max_damping_ns_per_m: 50.0,     // assumed
        workspace_radius_m: 0.2,
    }
}

/// Every preset, for menus and tests.
pub fn all() -> [DeviceSpecs; 9] {
    [
        touch(),
        phantom_omni(),
        phantom_desktop(),
        phantom_premium_6dof(),
        falcon(),
        inverse3(),
        omega(),
        sigma7(),
        delta3(),
    ]
}

/// The preset whose name contains `name` (case-insensitive), if any.
pub fn by_name(name: &str) -> Option<DeviceSpecs> {
    let wanted = name.to_ascii_lowercase();
    all().into_iter().find(|s| s.name.to_ascii_lowercase().contains(&wanted))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_preset_has_positive_limits_and_continuous_below_peak() {
        for s in all() {
            assert!(s.peak_force_n > 0.0 && s.max_stiffness_n_per_m > 0.0, "{}", s.name);
            assert!(s.continuous_force_n <= s.peak_force_n, "{}", s.name);
            assert_eq!(s.renders_torque(), s.max_torque_nm > 0.0, "{}", s.name);
        }
    }

    #[test]
    fn presets_are_found_by_part_of_their_name() {
        assert_eq!(by_name("falcon").map(|s| s.peak_force_n), Some(8.0));
        assert!(by_name("nonexistent").is_none());
    }
}
