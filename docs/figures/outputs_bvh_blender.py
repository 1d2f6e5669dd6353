# Run from the repository root: build/s2kf track data/handstand.c3d --out /tmp/o18/handstand --quiet && blender -b --factory-startup --python docs/figures/outputs_bvh_blender.py -- /tmp/o18/handstand.bvh docs/figures/outputs_bvh_blender.png 300
# The BVH written by `s2kf track`, imported in Blender at the importer's default settings and
# rendered headless (Workbench engine) at one frame: the figure in docs/outputs.md. Renders do not
# draw armatures, so each posed bone is drawn as a cylinder from its head to its tail, each joint
# as a sphere (left side blue, right side red, trunk grey).
import builtins
import sys

import addon_utils
import bpy
from mathutils import Vector

addon_utils.enable('io_anim_bvh')
import io_anim_bvh.import_bvh as importer  # noqa: E402

# Debian 12's blender 3.4 opens the file with mode 'rU', which Python 3.11 removed.
importer.open = lambda path, mode='r', *a, **k: builtins.open(path, mode.replace('U', ''), *a, **k)

bvh_path, png_path, frame = sys.argv[sys.argv.index('--') + 1:]
for thing in list(bpy.data.objects):
    bpy.data.objects.remove(thing)
bpy.ops.import_anim.bvh(filepath=bvh_path, update_scene_fps=True)
armature = bpy.context.active_object
armature.data.display_type = 'OCTAHEDRAL'
armature.show_in_front = True
scene = bpy.context.scene
scene.frame_set(int(frame))

# Frame the skeleton: the centre and size of its bone heads and tails at this frame.
points = [armature.matrix_world @ p for bone in armature.pose.bones for p in (bone.head, bone.tail)]
low = Vector([min(p[i] for p in points) for i in range(3)])
high = Vector([max(p[i] for p in points) for i in range(3)])
centre = (low + high) / 2
size = max(high - low)


def material(name, rgba):
    made = bpy.data.materials.new(name)
    made.diffuse_color = rgba
    return made


colours = {'L': material('left', (0.2, 0.4, 0.9, 1)), 'R': material('right', (0.9, 0.25, 0.2, 1)),
           '': material('trunk', (0.75, 0.75, 0.75, 1))}


def side(bone_name):
    return bone_name[0] if bone_name[0] in 'LR' and len(bone_name) <= 3 else ''


radius = 0.012 * size


def cylinder(start, end, thickness, colour):
    along = end - start
    if along.length > 1e-6:
        bpy.ops.mesh.primitive_cylinder_add(radius=thickness, depth=along.length, location=(start + end) / 2,
                                            rotation=along.to_track_quat('Z', 'Y').to_euler())
        bpy.context.active_object.data.materials.append(colour)


for bone in armature.pose.bones:
    head = armature.matrix_world @ bone.head
    tail = armature.matrix_world @ bone.tail
    bpy.ops.mesh.primitive_uv_sphere_add(radius=2 * radius, location=head)
    bpy.context.active_object.data.materials.append(colours[side(bone.name)])
    cylinder(head, tail, radius, colours[side(bone.name)])
    if bone.parent:  # the BVH OFFSET from the parent joint, where it is not the parent bone itself
        cylinder(armature.matrix_world @ bone.parent.head, head, 0.5 * radius, colours[''])
    print('bone %s head %s tail %s' % (bone.name, tuple(head), tuple(tail)))
armature.hide_render = True

bpy.ops.mesh.primitive_plane_add(size=4 * size, location=(centre.x, centre.y, min(0.0, low.z)))
bpy.context.active_object.data.materials.append(material('floor', (0.9, 0.9, 0.85, 1)))
camera_location = centre + Vector((1.2 * size, -2.6 * size, 0.7 * size))
bpy.ops.object.camera_add(location=camera_location)
camera = bpy.context.active_object
camera.rotation_euler = (centre - camera_location).to_track_quat('-Z', 'Y').to_euler()
scene.camera = camera
bpy.ops.object.light_add(type='SUN', location=centre + Vector((0, 0, 3 * size)))

scene.render.engine = 'BLENDER_WORKBENCH'
scene.display.shading.light = 'STUDIO'
scene.display.shading.color_type = 'MATERIAL'
scene.render.resolution_x = 800
scene.render.resolution_y = 600
scene.render.resolution_percentage = 100
scene.render.filepath = png_path
bpy.ops.render.render(write_still=True)
print('rendered frame %s of %s to %s' % (frame, bvh_path, png_path))
