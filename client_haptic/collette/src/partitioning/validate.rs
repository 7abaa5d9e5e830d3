//! Structural checks of a tree (run on every loaded file, so a crafted file cannot cause a panic).

use super::InnerSphereTree;

impl InnerSphereTree {
    /// Checks indices, ranges, finiteness, weights, that bounds wrap their leaves, that volumes and
    /// mesh shares add up and that every node is reachable from the root.
    pub fn validate(&self) -> Result<(), String> {
        if self.nodes.is_empty() {
            return Err("the tree has no root node".into());
        }
        if !self.mesh_volume.is_finite() || self.mesh_volume < 0.0 {
            return Err(format!("mesh volume {} is not a finite positive number", self.mesh_volume));
        }
        if let Some(i) = self
            .spheres
            .iter()
            .position(|s| !s.center.is_finite() || s.radius.is_nan() || s.radius < 0.0 || !s.radius.is_finite())
        {
            return Err(format!("sphere {i} has a non-finite centre or a bad radius"));
        }
        if self.weights.len() != self.spheres.len() {
            return Err(format!("{} weights for {} spheres", self.weights.len(), self.spheres.len()));
        }
        if let Some(i) = self.weights.iter().position(|w| !(w.is_finite() && *w > 0.0 && *w <= 1e6)) {
            return Err(format!("sphere {i} has weight {} (expected above 0, at most 1e6)", self.weights[i]));
        }
        let mut seen = vec![false; self.spheres.len()];
        let mut visited = vec![false; self.nodes.len()];
        let mut stack = vec![(0usize, 0usize)];
        while let Some((n, depth)) = stack.pop() {
            if depth > 64 {
                return Err("the hierarchy is deeper than 64 levels".into());
            }
            if std::mem::replace(&mut visited[n], true) {
                return Err(format!("node {n} is reachable twice"));
            }
            let node = &self.nodes[n];
            if !node.bound.center.is_finite()
                || !node.bound.radius.is_finite()
                || !node.volume.is_finite()
                || !node.mesh_share.is_finite()
            {
                return Err(format!("node {n} has non-finite values"));
            }
            let end = node.first as u64 + node.count as u64;
            if node.leaf {
                if end > self.spheres.len() as u64 {
                    return Err(format!("leaf {n} points past the sphere array"));
                }
                let (mut sum, mut share) = (0.0f64, 0.0f64);
                for s in node.range() {
                    if std::mem::replace(&mut seen[s], true) {
                        return Err(format!("sphere {s} belongs to two leaves"));
                    }
                    let sp = &self.spheres[s];
                    let slack = 1e-4 * node.bound.radius.max(sp.radius) + 1e-6;
                    if node.bound.center.distance(sp.center) + sp.radius > node.bound.radius + slack {
                        return Err(format!("leaf {n} does not enclose sphere {s}"));
                    }
                    sum += sp.volume() as f64;
                    share += sp.volume() as f64 * self.weights[s] as f64;
                }
                if !adds_up(node.volume, sum) {
                    return Err(format!("leaf {n} volume {} differs from its spheres' {sum}", node.volume));
                }
                if !adds_up(node.mesh_share, share) {
                    return Err(format!("leaf {n} mesh share {} differs from its spheres' {share}", node.mesh_share));
                }
            } else {
                if node.count == 0 || node.count > 4 || end > self.nodes.len() as u64 || (node.first as usize) <= n {
                    return Err(format!("inner node {n} has a bad child range (1 to 4 children after it)"));
                }
                let sum: f64 = node.range().map(|c| self.nodes[c].volume as f64).sum();
                if !adds_up(node.volume, sum) {
                    return Err(format!("node {n} volume {} differs from its children's {sum}", node.volume));
                }
                let share: f64 = node.range().map(|c| self.nodes[c].mesh_share as f64).sum();
                if !adds_up(node.mesh_share, share) {
                    return Err(format!("node {n} mesh share {} differs from its children's {share}", node.mesh_share));
                }
                for c in node.range() {
                    stack.push((c, depth + 1));
                }
            }
        }
        if let Some(s) = seen.iter().position(|s| !s) {
            return Err(format!("sphere {s} is in no leaf"));
        }
        // Every node is read when the child blocks are derived: none may escape the checks above.
        if let Some(n) = visited.iter().position(|v| !v) {
            return Err(format!("node {n} is not reachable from the root"));
        }
        Ok(())
    }
}

/// True when a stored sum matches the recomputed one within 0.1 % (f32 rounding of many terms).
fn adds_up(stored: f32, sum: f64) -> bool {
    (sum as f32 - stored).abs() <= 1e-3 * stored.max(1e-30) + 1e-30
}
