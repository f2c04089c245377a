// SPDX-License-Identifier: GPL-2.0
/*
 * hapticd-pwm-sim: a PWM chip with no hardware behind it, for hapticd's kernel tests.
 *
 * Debian's kernel has the PWM core and its sysfs interface (PWM=y, PWM_SYSFS=y) but no
 * virtual PWM driver, so the sysfs PWM output path of hapticd's GPIO driver would have
 * nothing to drive. This module registers a pwm_chip whose apply() only records the state
 * the PWM core hands it, and shows that record read-only in sysfs, one file per channel:
 *
 *   /sys/devices/platform/hapticd-pwm-sim/channelN
 *     period=<ns> duty_cycle=<ns> polarity=<normal|inversed> enabled=<0|1> applies=<n>
 *
 * One file per channel, so one read() is one consistent snapshot (a peer never sees a new
 * period with an old duty). Every apply() calls sysfs_notify() on the channel's file, so a
 * peer can poll() it (POLLPRI) and step its plant on each PWM write instead of spinning.
 * "applies" counts the calls the core made: the core skips apply() for an unchanged state.
 *
 * The chip itself appears as /sys/devices/platform/hapticd-pwm-sim/pwm/pwmchipN, the usual
 * sysfs PWM interface (export, period, duty_cycle, polarity, enable).
 */
#include <linux/module.h>
#include <linux/platform_device.h>
#include <linux/pwm.h>
#include <linux/slab.h>
#include <linux/spinlock.h>
#include <linux/sysfs.h>
#include <linux/version.h>

#define PWM_SIM_NAME "hapticd-pwm-sim"
#define PWM_SIM_MAX_CHANNELS 16

static unsigned int npwm = 2;
module_param(npwm, uint, 0444);
MODULE_PARM_DESC(npwm, "number of PWM channels (1-16, default 2)");

struct pwm_sim_channel {
	struct pwm_state applied;
	u64 applies;
	struct device_attribute attr;
	char name[16];
};

/* The platform device's driver data; the chip finds it through its parent device. */
struct pwm_sim {
	spinlock_t lock; /* guards every channel's applied state and count */
	struct pwm_sim_channel *channels;
	struct attribute **attrs;
	struct attribute_group group;
};

/*
 * Linux 6.9 made the PWM core allocate the chip, with a struct device of its own
 * (devm_pwmchip_alloc), and 6.7 dropped pwm_ops.owner: Debian 12 runs 6.1, Debian 13 6.12.
 */
#if LINUX_VERSION_CODE >= KERNEL_VERSION(6, 9, 0)
static struct device *pwm_sim_parent(struct pwm_chip *chip)
{
	return pwmchip_parent(chip);
}

static struct pwm_chip *pwm_sim_alloc_chip(struct device *dev)
{
	return devm_pwmchip_alloc(dev, npwm, 0);
}
#else
static struct device *pwm_sim_parent(struct pwm_chip *chip)
{
	return chip->dev;
}

static struct pwm_chip *pwm_sim_alloc_chip(struct device *dev)
{
	struct pwm_chip *chip = devm_kzalloc(dev, sizeof(*chip), GFP_KERNEL);

	if (!chip)
		return ERR_PTR(-ENOMEM);
	chip->dev = dev;
	chip->npwm = npwm;
	return chip;
}
#endif

static int pwm_sim_apply(struct pwm_chip *chip, struct pwm_device *pwm,
			 const struct pwm_state *state)
{
	struct pwm_sim *sim = dev_get_drvdata(pwm_sim_parent(chip));
	struct pwm_sim_channel *ch = &sim->channels[pwm->hwpwm];
	unsigned long flags;

	spin_lock_irqsave(&sim->lock, flags);
	ch->applied = *state;
	ch->applies++;
	spin_unlock_irqrestore(&sim->lock, flags);

	sysfs_notify(&pwm_sim_parent(chip)->kobj, NULL, ch->name);
	return 0;
}

/*
 * No get_state(): with it absent the core starts every channel from a zeroed state, which
 * is what a chip with no hardware has. (Its signature also changed within 6.1.y.)
 */
static const struct pwm_ops pwm_sim_ops = {
	.apply = pwm_sim_apply,
#if LINUX_VERSION_CODE < KERNEL_VERSION(6, 7, 0)
	.owner = THIS_MODULE,
#endif
};

static ssize_t pwm_sim_channel_show(struct device *dev, struct device_attribute *attr,
				    char *buf)
{
	struct pwm_sim *sim = dev_get_drvdata(dev);
	struct pwm_sim_channel *ch = container_of(attr, struct pwm_sim_channel, attr);
	struct pwm_state state;
	unsigned long flags;
	u64 applies;

	spin_lock_irqsave(&sim->lock, flags);
	state = ch->applied;
	applies = ch->applies;
	spin_unlock_irqrestore(&sim->lock, flags);

	return sysfs_emit(buf,
			  "period=%llu duty_cycle=%llu polarity=%s enabled=%d applies=%llu\n",
			  state.period, state.duty_cycle,
			  state.polarity == PWM_POLARITY_INVERSED ? "inversed" : "normal",
			  state.enabled ? 1 : 0, applies);
}

static int pwm_sim_add_channel_files(struct device *dev, struct pwm_sim *sim)
{
	unsigned int i;

	sim->channels = devm_kcalloc(dev, npwm, sizeof(*sim->channels), GFP_KERNEL);
	sim->attrs = devm_kcalloc(dev, npwm + 1, sizeof(*sim->attrs), GFP_KERNEL);
	if (!sim->channels || !sim->attrs)
		return -ENOMEM;

	for (i = 0; i < npwm; i++) {
		struct pwm_sim_channel *ch = &sim->channels[i];

		snprintf(ch->name, sizeof(ch->name), "channel%u", i);
		sysfs_attr_init(&ch->attr.attr);
		ch->attr.attr.name = ch->name;
		ch->attr.attr.mode = 0444;
		ch->attr.show = pwm_sim_channel_show;
		sim->attrs[i] = &ch->attr.attr;
	}
	sim->group.attrs = sim->attrs;
	return devm_device_add_group(dev, &sim->group);
}

static int pwm_sim_probe(struct platform_device *pdev)
{
	struct device *dev = &pdev->dev;
	struct pwm_chip *chip;
	struct pwm_sim *sim;
	int ret;

	sim = devm_kzalloc(dev, sizeof(*sim), GFP_KERNEL);
	if (!sim)
		return -ENOMEM;
	spin_lock_init(&sim->lock);
	platform_set_drvdata(pdev, sim);

	/* The channel files exist before the chip does, so whoever finds the chip can read them. */
	ret = pwm_sim_add_channel_files(dev, sim);
	if (ret)
		return ret;

	chip = pwm_sim_alloc_chip(dev);
	if (IS_ERR(chip))
		return PTR_ERR(chip);
	chip->ops = &pwm_sim_ops;
	return devm_pwmchip_add(dev, chip);
}

static struct platform_driver pwm_sim_driver = {
	.probe = pwm_sim_probe,
	.driver = { .name = PWM_SIM_NAME },
};

static struct platform_device *pwm_sim_device;

static int __init pwm_sim_init(void)
{
	int ret;

	if (npwm < 1 || npwm > PWM_SIM_MAX_CHANNELS)
		return -EINVAL;

	ret = platform_driver_register(&pwm_sim_driver);
	if (ret)
		return ret;

	pwm_sim_device = platform_device_register_simple(PWM_SIM_NAME, PLATFORM_DEVID_NONE,
							 NULL, 0);
	if (IS_ERR(pwm_sim_device)) {
		platform_driver_unregister(&pwm_sim_driver);
		return PTR_ERR(pwm_sim_device);
	}

	/* A failed probe is only logged by the driver core; fail the load instead. */
	if (!pwm_sim_device->dev.driver) {
		platform_device_unregister(pwm_sim_device);
		platform_driver_unregister(&pwm_sim_driver);
		return -ENODEV;
	}
	return 0;
}

static void __exit pwm_sim_exit(void)
{
	platform_device_unregister(pwm_sim_device);
	platform_driver_unregister(&pwm_sim_driver);
}

module_init(pwm_sim_init);
module_exit(pwm_sim_exit);

MODULE_DESCRIPTION("PWM chip without hardware that reports the applied state (hapticd tests)");
MODULE_LICENSE("GPL");
