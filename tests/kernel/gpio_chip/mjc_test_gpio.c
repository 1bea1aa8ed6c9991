// SPDX-License-Identifier: GPL-2.0
/*
 * mjc_test_gpio: a test-only GPIO chip for the kernel-layer tests of mjc's GPIO lines.
 *
 * Debian's kernel has no gpio-sim, gpio-mockup or irq simulator, but it has gpiolib
 * with its irqchip helpers and the GPIO character device. This module gives the test
 * VM a real /dev/gpiochipN (label "mjc-test-gpio", 8 lines) that libgpiod and mjc use
 * exactly as they would a lab's GPIO controller, with edge events.
 *
 * Each line is a wire. What the outside world applies to it ("input", set by the test)
 * is its level unless the chip drives it as an output; an open-drain output is
 * emulated by gpiolib (released = switched to input), so a released NRST line reads
 * whatever the test left on "input" (the board's pull-up: 1). A change of a wire's
 * level is counted, timed, and raises the line's interrupt when it is armed for that
 * edge, so the character device reports it as an edge event.
 *
 * debugfs, per line N (/sys/kernel/debug/mjc-test-gpio/N/):
 *   input        rw  0 or 1: the level the outside applies (default 0)
 *   level        r   the wire's level now: the output's value when driven, else input
 *   rising       r   rising edges of the wire since the module was loaded
 *   falling      r   falling edges
 *   last_low_ns  r   how long the wire last stayed low, from a falling to the next
 *                    rising edge (ktime, ns); 0 before the first such pulse
 * Writing "input" changes the level synchronously: its edge event is queued before
 * write() returns.
 */
#include <linux/bitmap.h>
#include <linux/debugfs.h>
#include <linux/gpio/driver.h>
#include <linux/irq.h>
#include <linux/irqdesc.h>
#include <linux/ktime.h>
#include <linux/module.h>
#include <linux/platform_device.h>
#include <linux/spinlock.h>
#include <linux/uaccess.h>

#define MJC_NGPIO 8

static const char *const mjc_line_names[MJC_NGPIO] = {
	"estop", "sync", "nrst1", "nrst2", "spare4", "spare5", "spare6", "spare7",
};

struct mjc_line {
	bool is_output;
	bool out_value;
	bool input;      /* what the outside applies */
	bool level;      /* the wire, last computed */
	bool armed;      /* interrupt unmasked */
	unsigned int irq_type;
	u64 fell_at_ns;
	/* read through debugfs */
	u32 rising;
	u32 falling;
	u64 last_low_ns;
	struct mjc_test_gpio *chip;
	unsigned int offset;
};

struct mjc_test_gpio {
	struct gpio_chip gc;
	spinlock_t lock;
	struct mjc_line lines[MJC_NGPIO];
	struct dentry *debugfs;
};

static struct platform_device *mjc_pdev;
static struct mjc_test_gpio *mjc_chip;

static bool mjc_wire(const struct mjc_line *l)
{
	return l->is_output ? l->out_value : l->input;
}

/*
 * Recomputes line `offset`'s level after a change, with the chip's lock held; returns
 * true when its interrupt must be raised (the caller does so after unlocking).
 */
static bool mjc_update_locked(struct mjc_test_gpio *chip, unsigned int offset)
{
	struct mjc_line *l = &chip->lines[offset];
	bool now = mjc_wire(l);
	bool fire = false;

	if (now == l->level)
		return false;
	l->level = now;
	if (now) {
		l->rising++;
		if (l->falling > 0)
			l->last_low_ns = ktime_get_ns() - l->fell_at_ns;
		fire = l->irq_type & IRQ_TYPE_EDGE_RISING;
	} else {
		l->falling++;
		l->fell_at_ns = ktime_get_ns();
		fire = l->irq_type & IRQ_TYPE_EDGE_FALLING;
	}
	return fire && l->armed;
}

static void mjc_change(struct mjc_test_gpio *chip, unsigned int offset,
		       void (*apply)(struct mjc_line *l, int value), int value)
{
	unsigned long flags;
	bool fire;

	spin_lock_irqsave(&chip->lock, flags);
	apply(&chip->lines[offset], value);
	fire = mjc_update_locked(chip, offset);
	spin_unlock_irqrestore(&chip->lock, flags);
	if (fire)
		generic_handle_domain_irq_safe(chip->gc.irq.domain, offset);
}

static void mjc_apply_input(struct mjc_line *l, int value) { l->input = value; }
static void mjc_apply_set(struct mjc_line *l, int value) { l->out_value = value; }
static void mjc_apply_out(struct mjc_line *l, int value)
{
	l->out_value = value;
	l->is_output = true;
}
static void mjc_apply_in(struct mjc_line *l, int value) { l->is_output = false; }

static int mjc_get_direction(struct gpio_chip *gc, unsigned int offset)
{
	struct mjc_test_gpio *chip = gpiochip_get_data(gc);

	return chip->lines[offset].is_output ? GPIO_LINE_DIRECTION_OUT
					     : GPIO_LINE_DIRECTION_IN;
}

static int mjc_direction_input(struct gpio_chip *gc, unsigned int offset)
{
	mjc_change(gpiochip_get_data(gc), offset, mjc_apply_in, 0);
	return 0;
}

static int mjc_direction_output(struct gpio_chip *gc, unsigned int offset, int value)
{
	mjc_change(gpiochip_get_data(gc), offset, mjc_apply_out, !!value);
	return 0;
}

static int mjc_get(struct gpio_chip *gc, unsigned int offset)
{
	struct mjc_test_gpio *chip = gpiochip_get_data(gc);
	unsigned long flags;
	int value;

	spin_lock_irqsave(&chip->lock, flags);
	value = mjc_wire(&chip->lines[offset]);
	spin_unlock_irqrestore(&chip->lock, flags);
	return value;
}

static void mjc_set(struct gpio_chip *gc, unsigned int offset, int value)
{
	mjc_change(gpiochip_get_data(gc), offset, mjc_apply_set, !!value);
}

/* The irq chip: edges only, armed and disarmed through gpiolib's helpers. */
static void mjc_irq_mask(struct irq_data *d)
{
	struct gpio_chip *gc = irq_data_get_irq_chip_data(d);
	struct mjc_test_gpio *chip = gpiochip_get_data(gc);
	irq_hw_number_t hwirq = irqd_to_hwirq(d);

	chip->lines[hwirq].armed = false;
	gpiochip_disable_irq(gc, hwirq);
}

static void mjc_irq_unmask(struct irq_data *d)
{
	struct gpio_chip *gc = irq_data_get_irq_chip_data(d);
	struct mjc_test_gpio *chip = gpiochip_get_data(gc);
	irq_hw_number_t hwirq = irqd_to_hwirq(d);

	gpiochip_enable_irq(gc, hwirq);
	chip->lines[hwirq].armed = true;
}

static int mjc_irq_set_type(struct irq_data *d, unsigned int type)
{
	struct gpio_chip *gc = irq_data_get_irq_chip_data(d);
	struct mjc_test_gpio *chip = gpiochip_get_data(gc);

	if (type & ~IRQ_TYPE_EDGE_BOTH)
		return -EINVAL; /* levels are not simulated */
	chip->lines[irqd_to_hwirq(d)].irq_type = type;
	return 0;
}

static const struct irq_chip mjc_irq_chip = {
	.name = "mjc-test-gpio",
	.irq_mask = mjc_irq_mask,
	.irq_unmask = mjc_irq_unmask,
	.irq_set_type = mjc_irq_set_type,
	.flags = IRQCHIP_IMMUTABLE | IRQCHIP_SKIP_SET_WAKE,
	GPIOCHIP_IRQ_RESOURCE_HELPERS,
};

/* debugfs "input": the level the outside world applies. */
static ssize_t mjc_input_write(struct file *file, const char __user *buf, size_t count,
			       loff_t *ppos)
{
	struct mjc_line *l = file->private_data;
	bool value;
	int ret = kstrtobool_from_user(buf, count, &value);

	if (ret)
		return ret;
	mjc_change(l->chip, l->offset, mjc_apply_input, value);
	return count;
}

static ssize_t mjc_input_read(struct file *file, char __user *buf, size_t count,
			      loff_t *ppos)
{
	struct mjc_line *l = file->private_data;
	char text[3] = { l->input ? '1' : '0', '\n', 0 };

	return simple_read_from_buffer(buf, count, ppos, text, 2);
}

static ssize_t mjc_level_read(struct file *file, char __user *buf, size_t count,
			      loff_t *ppos)
{
	struct mjc_line *l = file->private_data;
	char text[3] = { mjc_get(&l->chip->gc, l->offset) ? '1' : '0', '\n', 0 };

	return simple_read_from_buffer(buf, count, ppos, text, 2);
}

static const struct file_operations mjc_input_fops = {
	.owner = THIS_MODULE,
	.open = simple_open,
	.read = mjc_input_read,
	.write = mjc_input_write,
	.llseek = default_llseek,
};

static const struct file_operations mjc_level_fops = {
	.owner = THIS_MODULE,
	.open = simple_open,
	.read = mjc_level_read,
	.llseek = default_llseek,
};

static void mjc_debugfs_init(struct mjc_test_gpio *chip)
{
	unsigned int i;

	chip->debugfs = debugfs_create_dir("mjc-test-gpio", NULL);
	for (i = 0; i < MJC_NGPIO; i++) {
		struct mjc_line *l = &chip->lines[i];
		char name[8];
		struct dentry *dir;

		snprintf(name, sizeof(name), "%u", i);
		dir = debugfs_create_dir(name, chip->debugfs);
		debugfs_create_file("input", 0600, dir, l, &mjc_input_fops);
		debugfs_create_file("level", 0400, dir, l, &mjc_level_fops);
		debugfs_create_u32("rising", 0400, dir, &l->rising);
		debugfs_create_u32("falling", 0400, dir, &l->falling);
		debugfs_create_u64("last_low_ns", 0400, dir, &l->last_low_ns);
	}
}

static int __init mjc_test_gpio_init(void)
{
	struct mjc_test_gpio *chip;
	struct gpio_irq_chip *girq;
	unsigned int i;
	int ret;

	chip = kzalloc(sizeof(*chip), GFP_KERNEL);
	if (!chip)
		return -ENOMEM;
	spin_lock_init(&chip->lock);
	for (i = 0; i < MJC_NGPIO; i++) {
		chip->lines[i].chip = chip;
		chip->lines[i].offset = i;
	}

	mjc_pdev = platform_device_register_simple("mjc-test-gpio", PLATFORM_DEVID_NONE,
						   NULL, 0);
	if (IS_ERR(mjc_pdev)) {
		ret = PTR_ERR(mjc_pdev);
		goto free_chip;
	}

	chip->gc.label = "mjc-test-gpio";
	chip->gc.parent = &mjc_pdev->dev;
	chip->gc.owner = THIS_MODULE;
	chip->gc.base = -1;
	chip->gc.ngpio = MJC_NGPIO;
	chip->gc.names = mjc_line_names;
	chip->gc.can_sleep = false;
	chip->gc.get_direction = mjc_get_direction;
	chip->gc.direction_input = mjc_direction_input;
	chip->gc.direction_output = mjc_direction_output;
	chip->gc.get = mjc_get;
	chip->gc.set = mjc_set;

	girq = &chip->gc.irq;
	gpio_irq_chip_set_chip(girq, &mjc_irq_chip);
	girq->handler = handle_simple_irq;
	girq->default_type = IRQ_TYPE_NONE;
	girq->parent_handler = NULL;
	girq->num_parents = 0;
	girq->parents = NULL;

	ret = gpiochip_add_data(&chip->gc, chip);
	if (ret)
		goto unregister;
	mjc_debugfs_init(chip);
	mjc_chip = chip;
	return 0;

unregister:
	platform_device_unregister(mjc_pdev);
free_chip:
	kfree(chip);
	return ret;
}

static void __exit mjc_test_gpio_exit(void)
{
	debugfs_remove_recursive(mjc_chip->debugfs);
	gpiochip_remove(&mjc_chip->gc);
	platform_device_unregister(mjc_pdev);
	kfree(mjc_chip);
}

module_init(mjc_test_gpio_init);
module_exit(mjc_test_gpio_exit);

MODULE_DESCRIPTION("Test-only GPIO chip with edge events and debugfs-driven inputs");
MODULE_LICENSE("GPL");
