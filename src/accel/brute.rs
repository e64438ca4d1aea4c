//! Brute force: every ray against every primitive. The oracle of the tests.

use super::triangle::{moller_trumbore, WatertightRay};
use super::{Accel, AccelStats, Hit, TriangleTest};
use crate::math::Ray;
use crate::scene::{Cutouts, Mesh, Scene, Shape};
use std::sync::Arc;

/// Tests every object and every triangle.
pub struct BruteForce {
    objects: Vec<BruteObject>,
    test: TriangleTest,
    cutouts: Option<Arc<Cutouts>>,
}

enum BruteObject {
    Sphere(crate::scene::Sphere),
    Quad(crate::scene::Quad),
    Disk(crate::scene::Disk),
    Cylinder(crate::scene::Cylinder),
    Mesh(Arc<Mesh>, crate::math::Transform),
}

impl BruteForce {
    /// Wraps the scene's objects.
    pub fn new(scene: &Scene, test: TriangleTest) -> Self {
        let objects = scene
            .objects
            .iter()
            .map(|o| match &o.shape {
                Shape::Sphere(s) => BruteObject::Sphere(*s),
                Shape::Quad(q) => BruteObject::Quad(*q),
                Shape::Disk(d) => BruteObject::Disk(*d),
                Shape::Cylinder(c) => BruteObject::Cylinder(*c),
                Shape::Mesh { mesh, transform, .. } => {
                    BruteObject::Mesh(scene.meshes[*mesh as usize].clone(), *transform)
                }
            })
            .collect();
        Self {
            objects,
            test,
            cutouts: Cutouts::of(scene),
        }
    }

    fn query(&self, ray: &Ray, t_max: f32, any: bool) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut t_max = t_max;
        for (i, object) in self.objects.iter().enumerate() {
            let instance = i as u32;
            match object {
                BruteObject::Sphere(s) => {
                    let t = match &self.cutouts {
                        Some(c) => c.sphere(instance, s, ray, t_max),
                        None => s.intersect(ray, t_max),
                    };
                    if let Some(t) = t {
                        best = Some(Hit {
                            t,
                            instance,
                            prim: 0,
                            u: 0.0,
                            v: 0.0,
                        });
                        t_max = t;
                    }
                }
                BruteObject::Quad(q) => {
                    let h = match &self.cutouts {
                        Some(c) => c.quad(instance, q, ray, t_max),
                        None => q.intersect(ray, t_max),
                    };
                    if let Some((t, u, v)) = h {
                        best = Some(Hit {
                            t,
                            instance,
                            prim: 0,
                            u,
                            v,
                        });
                        t_max = t;
                    }
                }
                BruteObject::Disk(d) => {
                    let h = match &self.cutouts {
                        Some(c) => c.disk(instance, d, ray, t_max),
                        None => d.intersect(ray, t_max),
                    };
                    if let Some((t, u, v)) = h {
                        best = Some(Hit {
                            t,
                            instance,
                            prim: 0,
                            u,
                            v,
                        });
                        t_max = t;
                    }
                }
                BruteObject::Cylinder(cyl) => {
                    let t = match &self.cutouts {
                        Some(c) => c.cylinder(instance, cyl, ray, t_max),
                        None => cyl.intersect(ray, t_max),
                    };
                    if let Some(t) = t {
                        best = Some(Hit {
                            t,
                            instance,
                            prim: 0,
                            u: 0.0,
                            v: 0.0,
                        });
                        t_max = t;
                    }
                }
                BruteObject::Mesh(mesh, transform) => {
                    let local = transform.ray_to_object(ray);
                    let wt = WatertightRay::new(&local);
                    for prim in 0..mesh.triangles.len() {
                        let [p0, p1, p2] = mesh.corners(prim);
                        let h = match self.test {
                            TriangleTest::Watertight => wt.intersect(p0, p1, p2, t_max),
                            TriangleTest::MollerTrumbore => moller_trumbore(&local, p0, p1, p2, t_max),
                        };
                        let kept = |&(_, u, v): &(f32, f32, f32)| {
                            self.cutouts
                                .as_ref()
                                .is_none_or(|c| c.keeps_triangle(instance, prim as u32, u, v))
                        };
                        if let Some((t, u, v)) = h.filter(kept) {
                            best = Some(Hit {
                                t,
                                instance,
                                prim: prim as u32,
                                u,
                                v,
                            });
                            t_max = t;
                            if any {
                                return best;
                            }
                        }
                    }
                }
            }
            if any && best.is_some() {
                return best;
            }
        }
        best
    }
}

impl Accel for BruteForce {
    fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        self.query(ray, t_max, false)
    }

    fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        self.query(ray, t_max, true).is_some()
    }

    fn stats(&self) -> AccelStats {
        AccelStats {
            name: "brute".into(),
            instances: self.objects.len(),
            ..Default::default()
        }
    }
}
