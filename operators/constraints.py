"""Operators that edit the semi-supervision: style labels (paper eq. 2) and triplets (eq. 3).

Labels live in `scene.style_coanalysis.labels`; an object carries the name of its label in
`object.style_coanalysis.label`. Triplets are PointerProperties to the three objects.
"""
import bpy
from bpy.props import FloatVectorProperty, IntProperty, StringProperty

PALETTE = ((0.90, 0.30, 0.20, 1.0), (0.20, 0.55, 0.90, 1.0), (0.30, 0.75, 0.30, 1.0),
           (0.95, 0.75, 0.15, 1.0), (0.60, 0.35, 0.80, 1.0), (0.15, 0.75, 0.75, 1.0))


def _settings(context):
    return context.scene.style_coanalysis


def _resolve_index(labels_or_triplets, index, active):
    i = active if index < 0 else index
    return i if 0 <= i < len(labels_or_triplets) else None


def _selected_meshes(context):
    return [o for o in context.selected_objects if o.type == "MESH"]


# ------------------------------------------------------------------------------------ labels

class STYLE_OT_label_add(bpy.types.Operator):
    """Add a style label"""

    bl_idname = "style.label_add"
    bl_label = "Add Style Label"
    bl_options = {"REGISTER", "UNDO"}

    name: StringProperty(name="Name", default="", description="Empty: 'Style N'")

    @classmethod
    def poll(cls, context):
        if context.scene is None:
            cls.poll_message_set("No scene")
            return False
        return True

    def execute(self, context):
        settings = _settings(context)
        existing = set(settings.label_names())
        wanted = self.name.strip()
        if not wanted:
            n = len(settings.labels) + 1
            while f"Style {n}" in existing:
                n += 1
            wanted = f"Style {n}"
        label = settings.labels.add()
        label.color = PALETTE[(len(settings.labels) - 1) % len(PALETTE)]
        label.name = wanted                     # the update callback makes it unique
        settings.active_label_index = len(settings.labels) - 1
        self.report({"INFO"}, f"Added label '{label.name}'")
        return {"FINISHED"}


class _LabelIndexOperator:
    index: IntProperty(name="Index", default=-1, description="Label index (-1: the active one)")

    @classmethod
    def poll(cls, context):
        if context.scene is None or not len(_settings(context).labels):
            cls.poll_message_set("There are no style labels: add one first")
            return False
        return True

    def _label(self, context):
        settings = _settings(context)
        i = _resolve_index(settings.labels, self.index, settings.active_label_index)
        if i is None:
            self.report({"ERROR"}, f"No style label at index {self.index}")
        return i


class STYLE_OT_label_remove(_LabelIndexOperator, bpy.types.Operator):
    """Remove a style label; objects that carried it become unlabelled"""

    bl_idname = "style.label_remove"
    bl_label = "Remove Style Label"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        i = self._label(context)
        if i is None:
            return {"CANCELLED"}
        settings = _settings(context)
        name = settings.labels[i].name
        n = 0
        for obj in bpy.data.objects:
            if obj.style_coanalysis.label == name:
                obj.style_coanalysis.label = ""
                n += 1
        settings.labels.remove(i)
        settings.active_label_index = min(i, len(settings.labels) - 1) if len(settings.labels) else 0
        self.report({"INFO"}, f"Removed label '{name}' from {n} objects")
        return {"FINISHED"}


class STYLE_OT_label_rename(_LabelIndexOperator, bpy.types.Operator):
    """Rename a style label; objects that carry it follow"""

    bl_idname = "style.label_rename"
    bl_label = "Rename Style Label"
    bl_options = {"REGISTER", "UNDO"}

    name: StringProperty(name="Name")

    def execute(self, context):
        i = self._label(context)
        if i is None:
            return {"CANCELLED"}
        if not self.name.strip():
            self.report({"ERROR"}, "A style label needs a name")
            return {"CANCELLED"}
        labels = _settings(context).labels
        name = self.name.strip()
        if any(lab.name == name for j, lab in enumerate(labels) if j != i):
            self.report({"ERROR"}, f"There is already a style label '{name}'")
            return {"CANCELLED"}
        labels[i].name = name          # update callback renames objects' labels
        return {"FINISHED"}


class STYLE_OT_label_color(_LabelIndexOperator, bpy.types.Operator):
    """Set a style label's colour"""

    bl_idname = "style.label_color"
    bl_label = "Style Label Colour"
    bl_options = {"REGISTER", "UNDO"}

    color: FloatVectorProperty(name="Colour", subtype="COLOR", size=4, min=0.0, max=1.0,
                               default=(0.8, 0.5, 0.1, 1.0))

    def execute(self, context):
        i = self._label(context)
        if i is None:
            return {"CANCELLED"}
        _settings(context).labels[i].color = self.color
        return {"FINISHED"}


class STYLE_OT_label_assign(_LabelIndexOperator, bpy.types.Operator):
    """Give the active style label to the selected mesh objects"""

    bl_idname = "style.label_assign"
    bl_label = "Assign Label"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if not super().poll(context):
            return False
        if not _selected_meshes(context):
            cls.poll_message_set("Select the mesh objects to label")
            return False
        return True

    def execute(self, context):
        i = self._label(context)
        if i is None:
            return {"CANCELLED"}
        name = _settings(context).labels[i].name
        objs = _selected_meshes(context)
        for obj in objs:
            obj.style_coanalysis.label = name
        self.report({"INFO"}, f"Labelled {len(objs)} objects '{name}'")
        return {"FINISHED"}


class STYLE_OT_label_clear(bpy.types.Operator):
    """Remove the style label from the selected objects"""

    bl_idname = "style.label_clear"
    bl_label = "Clear Label"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if not any(o.style_coanalysis.label for o in context.selected_objects):
            cls.poll_message_set("None of the selected objects has a style label")
            return False
        return True

    def execute(self, context):
        n = 0
        for obj in context.selected_objects:
            if obj.style_coanalysis.label:
                obj.style_coanalysis.label = ""
                n += 1
        self.report({"INFO"}, f"Cleared the label of {n} objects")
        return {"FINISHED"}


# ---------------------------------------------------------------------------------- triplets

TRIPLET_HINT = "Set A, B and C in the panel, or select three meshes with A active"


def triplet_from_context(context):
    """(a, b, c) object names from the panel's A/B/C fields, else from the selection (active = A,
    the two other selected meshes = B then C by name). None when neither gives three."""
    s = _settings(context)
    if s.triplet_a and s.triplet_b and s.triplet_c:
        return s.triplet_a.name, s.triplet_b.name, s.triplet_c.name
    active = context.active_object
    others = sorted(o.name for o in _selected_meshes(context) if o != active)
    if active is not None and active.type == "MESH" and active.select_get() and len(others) == 2:
        return active.name, others[0], others[1]
    return None


class STYLE_OT_triplet_add(bpy.types.Operator):
    """Add the constraint "A is closer in style to B than to C" (A, B, C from the panel, or the
    active object as A and the two other selected meshes as B and C)"""

    bl_idname = "style.triplet_add"
    bl_label = "Add Triplet"
    bl_options = {"REGISTER", "UNDO"}

    a: StringProperty(name="A", description="Object name (empty: from the panel or selection)")
    b: StringProperty(name="B")
    c: StringProperty(name="C")

    @classmethod
    def poll(cls, context):
        if context.scene is None:
            cls.poll_message_set("No scene")
            return False
        # Not stricter: scripts pass a, b, c by name whatever the selection; the panel disables
        # its button with a hint when neither the fields nor the selection give three meshes.
        if sum(o.type == "MESH" for o in context.scene.objects) < 3:
            cls.poll_message_set("A triplet needs three mesh objects in the scene")
            return False
        return True

    def execute(self, context):
        if self.a or self.b or self.c:
            names = (self.a, self.b, self.c)
        else:
            names = triplet_from_context(context)
        if names is None:
            self.report({"ERROR"}, f"{TRIPLET_HINT}")
            return {"CANCELLED"}
        objs = []
        for n in names:
            obj = bpy.data.objects.get(n)
            if obj is None or obj.type != "MESH":
                self.report({"ERROR"}, f"'{n}' is not a mesh object")
                return {"CANCELLED"}
            objs.append(obj)
        if len(set(names)) != 3:
            self.report({"ERROR"}, f"A, B and C must be three different objects, got {names}")
            return {"CANCELLED"}
        settings = _settings(context)
        for t in settings.triplets:
            if t.names() == names:
                self.report({"INFO"}, f"Triplet {names} already exists")
                return {"CANCELLED"}
            if t.names() == (names[0], names[2], names[1]):
                self.report({"WARNING"}, f"This contradicts the triplet {t.names()}")
        t = settings.triplets.add()
        t.a, t.b, t.c = objs
        settings.active_triplet_index = len(settings.triplets) - 1
        self.report({"INFO"}, f"'{names[0]}' is closer in style to '{names[1]}' "
                              f"than to '{names[2]}'")
        return {"FINISHED"}


class _TripletIndexOperator:
    index: IntProperty(name="Index", default=-1, description="Triplet index (-1: the active one)")

    @classmethod
    def poll(cls, context):
        if context.scene is None or not len(_settings(context).triplets):
            cls.poll_message_set("There are no triplets")
            return False
        return True

    def _triplet(self, context):
        s = _settings(context)
        i = _resolve_index(s.triplets, self.index, s.active_triplet_index)
        if i is None:
            self.report({"ERROR"}, f"No triplet at index {self.index}")
        return i


class STYLE_OT_triplet_remove(_TripletIndexOperator, bpy.types.Operator):
    """Delete a triplet constraint"""

    bl_idname = "style.triplet_remove"
    bl_label = "Delete Triplet"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        i = self._triplet(context)
        if i is None:
            return {"CANCELLED"}
        s = _settings(context)
        s.triplets.remove(i)
        s.active_triplet_index = min(i, len(s.triplets) - 1) if len(s.triplets) else 0
        return {"FINISHED"}


class STYLE_OT_triplet_swap(_TripletIndexOperator, bpy.types.Operator):
    """Swap B and C of a triplet (A is closer to C than to B)"""

    bl_idname = "style.triplet_swap"
    bl_label = "Swap B and C"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        i = self._triplet(context)
        if i is None:
            return {"CANCELLED"}
        t = _settings(context).triplets[i]
        t.b, t.c = t.c, t.b
        return {"FINISHED"}


CLASSES = (STYLE_OT_label_add, STYLE_OT_label_remove, STYLE_OT_label_rename, STYLE_OT_label_color,
           STYLE_OT_label_assign, STYLE_OT_label_clear, STYLE_OT_triplet_add,
           STYLE_OT_triplet_remove, STYLE_OT_triplet_swap)
